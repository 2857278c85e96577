// `clothbake query ASSET radiance` (radiance_query_command.hpp).
#include "bake/cli/radiance_query_command.hpp"

#include <cmath>
#include <sstream>

#include "common/error.hpp"
#include "formats/reader/compressed_tables.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "formats/writer/open_asset.hpp"

namespace clothbake::cli {

nlohmann::json radiance_query(const reader::Asset& asset, const RadianceQueryArgs& args) {
  static const char* const kLobes[] = {"specular_reflection", "specular_transmission",
                                       "diffuse_reflection",  "diffuse_transmission",
                                       "delta_transmission",  "sheen"};
  bool known = false;
  for (const char* l : kLobes)
    known = known || args.lobe == l;
  if (!known)
    throw Error(ExitCode::Usage, "--lobe: unknown lobe '" + args.lobe +
                                     "' (specular_reflection, specular_transmission, "
                                     "delta_transmission have tables)");
  reader::RadianceTableKind kind;
  if (!reader::radiance_kind_of_lobe(args.lobe.c_str(), &kind))
    throw Error(ExitCode::Usage,
                "--lobe: " + args.lobe +
                    " has no Integral-Radiance table (diffuse and sheen lobes are not tabulated; "
                    "use specular_reflection, specular_transmission or delta_transmission)");
  // Compressed tables first under Auto (what a renderer reads); the raw ones when the asset has
  // no compressed ones.
  using eval::TableChoice;
  reader::RawRadianceTables raw;
  reader::CompressedRadianceTables compressed;
  const reader::RadianceTables* chosen = nullptr;
  reader::Status status;
  if (args.source != TableChoice::Raw) {
    status = compressed.open(asset, kind);
    if (status.ok()) chosen = &compressed;
  }
  if (!chosen && args.source != TableChoice::Compressed &&
      (args.source == TableChoice::Raw || status.code() == reader::ErrorCode::NotFound)) {
    status = raw.open(asset, kind);
    if (status.ok()) chosen = &raw;
  }
  if (!chosen) {
    if (status.code() == reader::ErrorCode::NotFound) {
      const char* which = args.source == TableChoice::Raw          ? " raw"
                          : args.source == TableChoice::Compressed ? " compressed"
                                                                   : "";
      throw_input_error("the asset has no" + std::string(which) + " " +
                        reader::radiance_kind_name(kind) + " table for " + args.lobe +
                        (kind == reader::RadianceTableKind::Gap
                             ? " (the fabric has no gaps, so nothing is transmitted through them)"
                             : ""));
    }
    throw Error(formats::exit_code_of(status), formats::describe(status));
  }
  const reader::RadianceTables& tables = *chosen;
  const bool is_raw = chosen == &raw;
  auto stored = [&](uint32_t c) {
    return is_raw ? raw.column_of_cluster(c) >= 0 : compressed.has_cluster(c);
  };
  if (args.cluster && *args.cluster >= tables.cluster_count())
    throw Error(ExitCode::Usage, "--cluster: " + std::to_string(*args.cluster) +
                                     " is out of range (the asset has " +
                                     std::to_string(tables.cluster_count()) + " clusters)");
  const reader::Footprint rect{args.rect[0], args.rect[1], args.rect[2], args.rect[3]};
  reader::FootprintPlan plan;
  if (const reader::Status s = reader::plan_footprint(rect, tables.resolution(), &plan); !s.ok())
    throw Error(ExitCode::Usage, std::string("--rect: ") + s.message());
  reader::BinWeights weights;
  if (const reader::Status s =
          reader::radiance_bin_weights(tables.bins_per_side(), args.h.data(), &weights);
      !s.ok())
    throw Error(ExitCode::Usage, std::string("--h: ") + s.message());

  std::vector<double> f(tables.cluster_count(), 0.0);
  if (!tables.covers_bins(args.h.data()))  // a scene-planned asset: OutOfPlan, exit 2
    formats::throw_if_failed(tables.query_all(rect, args.h.data(), f.data()), "--h");
  if (args.cluster) {
    if (!tables.query(rect, args.h.data(), *args.cluster, &f[*args.cluster]).ok())
      throw_internal_error("radiance query rejected validated arguments");
  } else if (!tables.query_all(rect, args.h.data(), f.data()).ok()) {
    throw_internal_error("radiance query rejected validated arguments");
  }
  const double area = (rect.x1 - rect.x0) * (rect.y1 - rect.y0);
  nlohmann::json clusters = nlohmann::json::array();
  double total = 0;
  for (uint32_t c = 0; c < tables.cluster_count(); ++c) {
    if (args.cluster && c != *args.cluster) continue;
    total += f[c];
    clusters.push_back({{"cluster", c},
                        {"stored", stored(c)},
                        {"F", f[c]},
                        {"average", area > 0 ? f[c] / area : 0.0}});
  }
  nlohmann::json bins = nlohmann::json::array();
  for (uint32_t k = 0; k < weights.count; ++k)
    bins.push_back({{"bin", weights.bin[k]}, {"weight", weights.weight[k]}});
  return {{"lobe", args.lobe},
          {"table", reader::radiance_kind_name(kind)},
          {"source", is_raw ? "raw" : "compressed"},
          {"resolution", tables.resolution()},
          {"bins_per_side", tables.bins_per_side()},
          {"h", args.h},
          {"bins", bins},
          {"rect", args.rect},
          {"area_texels", area},
          {"units",
           "F: sum over texels of the table value times the covered area (texel^2); "
           "average = F / area"},
          {"clusters", clusters},
          {"total", total},
          {"total_average", area > 0 ? total / area : 0.0}};
}

std::string radiance_query_text(const nlohmann::json& a) {
  std::ostringstream out;
  out.precision(9);
  const auto& r = a["rect"];
  out << a["lobe"].get<std::string>() << " (" << a["table"].get<std::string>() << " table, "
      << a.value("source", std::string("raw")) << ") over [" << r[0].get<double>() << ", "
      << r[2].get<double>() << ") x [" << r[1].get<double>() << ", " << r[3].get<double>()
      << "), h (" << a["h"][0].get<double>() << ", " << a["h"][1].get<double>() << ", "
      << a["h"][2].get<double>() << ")\n";
  for (const auto& c : a["clusters"])
    out << "  cluster " << c["cluster"].get<uint32_t>() << ": F = " << c["F"].get<double>()
        << "  (average " << c["average"].get<double>() << ")"
        << (c["stored"].get<bool>() ? "" : "  [no table: zero]") << "\n";
  out << "  total: F = " << a["total"].get<double>() << "  (average "
      << a["total_average"].get<double>() << ")\n";
  return out.str();
}

}  // namespace clothbake::cli
