// clothbake export ASSET --section S [--instance I] [--index i,j,...] -o FILE.exr [--force]:
// writes one section of an asset as an image for looking at it (common/image_io/image_io.hpp; the
// format follows the extension, EXR keeps float values). --index fixes the leading dimensions until
// an image is left: {H, W} (one channel), {H, W, C} with C <= 4, or {W} (one row). Integer elements
// are converted to float unchanged (not normalised). The section's checksum is verified first.
// Exit 3 for a corrupt asset, 2 for a bad section name, index or output path.
//
// Integral-Radiance tables are exported as tables, not as their stored bytes:
//   --section radiance_tables     [--lobe L] --index bin[,cluster]   (raw fixed-point SATs)
//   --section radiance_compressed [--lobe L] --index bin[,cluster]   (C-PCA, decompressed)
// write the per-texel values T[cluster][bin] (N x N, one channel; without a cluster the sum over
// every cluster, i.e. the whole tile's table of that bin). L is a lobe name of `clothbake bsdf`
// (default specular_reflection; delta_transmission reads the gap table, which has one bin). The
// cluster label map is the typed section cluster_labels (u8 {N, N}).
#include <filesystem>
#include <memory>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "common/diagnostics.hpp"
#include "common/image_io/image_io.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/compressed_tables.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "formats/validate/checksums.hpp"
#include "formats/writer/atomic_file.hpp"
#include "formats/writer/open_asset.hpp"
#include "formats/writer/valid_asset.hpp"
#include "render/image_output.hpp"

namespace clothbake::cli {
namespace {

using namespace clothbake::reader;

struct ExportOptions {
  std::string asset;
  std::string section;
  uint32_t instance = 0;
  std::vector<uint32_t> index;
  std::string output;
  std::string lobe;
  bool force = false;
};

SectionType parse_section(const std::string& text) {
  SectionType type;
  if (section_type_from_name(text.c_str(), &type)) return type;
  try {
    std::size_t used = 0;
    const unsigned long value = std::stoul(text, &used, 0);  // decimal or 0x...
    if (used == text.size() && value <= 0xffffffffu) return SectionType(uint32_t(value));
  } catch (const std::exception&) {
  }
  throw_input_error("unknown section '" + text +
                    "': give a section name (height, normal, parallax, ...) or a numeric type id");
}

float element_as_float(const unsigned char* p, ElementType type) {
  auto load = [p](auto v) {
    std::memcpy(&v, p, sizeof v);
    return v;
  };
  switch (type) {
    case ElementType::U8:
      return float(load(uint8_t{}));
    case ElementType::I8:
      return float(load(int8_t{}));
    case ElementType::U16:
      return float(load(uint16_t{}));
    case ElementType::I16:
      return float(load(int16_t{}));
    case ElementType::U32:
      return float(load(uint32_t{}));
    case ElementType::I32:
      return float(load(int32_t{}));
    case ElementType::U64:
      return float(load(uint64_t{}));
    case ElementType::I64:
      return float(load(int64_t{}));
    case ElementType::F16:
      return half_to_float(Half{load(uint16_t{})});
    case ElementType::F32:
      return load(float{});
    case ElementType::F64:
      return float(load(double{}));
    case ElementType::Opaque:
      break;
  }
  return 0.f;
}

std::string shape_text(const SectionInfo& s) {
  std::string text = "{";
  for (uint32_t d = 0; d < s.rank; ++d)
    text += (d ? ", " : "") + std::to_string(s.dims[d]);
  return text + "}";
}

Image section_image(const SectionInfo& s, const std::vector<uint32_t>& index,
                    const std::string& label) {
  if (s.codec != Codec::Raw || s.element_type == ElementType::Opaque ||
      element_size(s.element_type) == 0)
    throw_input_error("section " + label + " is not a typed array that can be shown as an image");
  if (index.size() > s.rank)
    throw_input_error("section " + label + " has shape " + shape_text(s) + ": --index has " +
                      std::to_string(index.size()) + " values, at most " + std::to_string(s.rank) +
                      " are possible");
  uint64_t offset = 0;  // in elements
  uint64_t stride = 1;
  for (uint32_t d = s.rank; d-- > 0;) {
    if (d < index.size()) {
      if (index[d] >= s.dims[d])
        throw_input_error("section " + label + " has shape " + shape_text(s) + ": --index value " +
                          std::to_string(index[d]) + " is out of range for dimension " +
                          std::to_string(d) + " (size " + std::to_string(s.dims[d]) + ")");
      offset += index[d] * stride;
    }
    stride *= s.dims[d];
  }
  std::vector<uint32_t> rest(s.dims + index.size(), s.dims + s.rank);
  int width, height, channels;
  if (rest.size() == 1) {
    height = 1, width = int(rest[0]), channels = 1;
  } else if (rest.size() == 2) {
    height = int(rest[0]), width = int(rest[1]), channels = 1;
  } else if (rest.size() == 3 && rest[2] <= 4) {
    height = int(rest[0]), width = int(rest[1]), channels = int(rest[2]);
  } else {
    const std::size_t needed = s.rank - (s.dims[s.rank - 1] <= 4 ? 3 : 2);
    throw_input_error("section " + label + " has shape " + shape_text(s) + ": give --index with " +
                      std::to_string(needed) + " value(s) to select an image");
  }
  if (width <= 0 || height <= 0 || channels <= 0)
    throw_input_error("section " + label + " is empty: nothing to export");
  Image image(width, height, channels);
  const uint32_t size = element_size(s.element_type);
  for (std::size_t i = 0; i < image.pixels.size(); ++i)
    image.pixels[i] = element_as_float(s.data + (offset + i) * size, s.element_type);
  return image;
}

// A typed section (instance o.instance) as an image, after verifying its checksum.
Image section_export_image(const Asset& asset, const ExportOptions& o, SectionType type) {
  SectionInfo section;
  Status status = asset.find(type, o.instance, &section);
  if (!status.ok()) throw_input_error(o.asset + ": " + status.message());
  status = reader::verify_section(asset, section);
  if (!status.ok()) throw Error(ExitCode::InvalidAsset, o.asset + ": " + formats::describe(status));
  const std::string label = o.section + " (instance " + std::to_string(o.instance) + ")";
  // The coded feature maps (16-bit codes, entropy-coded) are exported as the floats the reader
  // decodes them to.
  const uint32_t t = uint32_t(type);
  if (t >= 0x0100 && t <= 0x0105 && t != 0x0104 && o.instance == 0) {
    reader::FeatureMaps maps;
    status = reader::read_feature_maps(asset, &maps);
    if (!status.ok())
      throw Error(ExitCode::InvalidAsset, o.asset + ": " + formats::describe(status));
    const reader::ArrayView<float>& view =
        t == 0x0100
            ? maps.height
            : (t == 0x0101 ? maps.tangent
                           : (t == 0x0102 ? maps.normal : (t == 0x0103 ? maps.gap : maps.albedo)));
    SectionInfo decoded = section;
    decoded.codec = Codec::Raw;
    decoded.element_type = ElementType::F32;
    decoded.rank = view.rank;
    for (uint32_t d = 0; d < reader::kMaxRank; ++d)
      decoded.dims[d] = view.dims[d];
    decoded.data = reinterpret_cast<const unsigned char*>(view.data);
    return section_image(decoded, o.index, label);
  }
  return section_image(section, o.index, label);
}

// The table of one (bin, cluster), or of one bin summed over every cluster, of kind's raw or
// compressed Integral-Radiance tables, as an N x N image of per-texel values.
Image radiance_image(const Asset& asset, const std::string& asset_path, bool compressed,
                     const std::string& lobe, const std::vector<uint32_t>& index) {
  RadianceTableKind kind;
  if (!radiance_kind_of_lobe(lobe.c_str(), &kind))
    throw Error(ExitCode::Usage, "--lobe: '" + lobe +
                                     "' has no Integral-Radiance table (specular_reflection, "
                                     "specular_transmission and delta_transmission have one)");
  const std::string label = std::string(compressed ? "radiance_compressed" : "radiance_tables") +
                            " (" + radiance_kind_name(kind) + ")";
  RawRadianceTables raw;
  CompressedRadianceTables packed;
  const Status status = compressed ? packed.open(asset, kind) : raw.open(asset, kind);
  if (status.code() == ErrorCode::NotFound)
    throw_input_error(asset_path + ": no " + label + " tables in the asset (" + status.message() +
                      ")");
  if (!status.ok())
    throw Error(formats::exit_code_of(status), asset_path + ": " + formats::describe(status));
  const RadianceTables& tables = compressed ? static_cast<const RadianceTables&>(packed) : raw;
  const uint32_t n = tables.resolution();
  const uint32_t bins = tables.bins_per_side() * tables.bins_per_side();
  if (index.empty() || index.size() > 2)
    throw_input_error("section " + label + ": give --index bin or --index bin,cluster (" +
                      std::to_string(bins) + " bins, " + std::to_string(tables.cluster_count()) +
                      " clusters)");
  if (index[0] >= bins)
    throw_input_error("section " + label + ": --index bin " + std::to_string(index[0]) +
                      " is out of range (" + std::to_string(bins) + " bins)");
  if (index.size() == 2 && index[1] >= tables.cluster_count())
    throw_input_error("section " + label + ": --index cluster " + std::to_string(index[1]) +
                      " is out of range (" + std::to_string(tables.cluster_count()) + " clusters)");
  Image image(static_cast<int>(n), static_cast<int>(n), 1);
  const uint32_t bin = index[0];
  if (!compressed) {
    std::vector<float> one(std::size_t(n) * n);
    for (uint32_t c = 0; c < tables.cluster_count(); ++c) {
      if (index.size() == 2 && c != index[1]) continue;
      if (raw.column_of_cluster(c) < 0) continue;  // zero
      if (!raw.texel_image(bin, c, one.data()).ok())
        throw_internal_error("texel_image rejected a checked bin and cluster");
      for (std::size_t t = 0; t < one.size(); ++t)
        image.pixels[t] += one[t];
    }
  } else {
    for (uint32_t y = 0; y < n; ++y)
      for (uint32_t x = 0; x < n; ++x) {
        const int c = packed.cluster_of_texel(x, y);
        if (c < 0 || (index.size() == 2 && uint32_t(c) != index[1])) continue;
        image.pixels[std::size_t(y) * n + x] = float(packed.texel_value(bin, x, y));
      }
  }
  return image;
}

Action setup_export(CLI::App& app) {
  auto o = std::make_shared<ExportOptions>();
  add_asset_argument(app, o->asset);
  app.add_option("--section", o->section, "section name (see `clothbake info`) or type id")
      ->required();
  app.add_option("--instance", o->instance, "instance of the section (default 0)");
  app.add_option("--index", o->index, "fix the leading dimensions, e.g. --index 3 or 3,0")
      ->delimiter(',');
  app.add_option("-o,--output", o->output, "image to write (.exr keeps floats; .png, .tif)")
      ->required();
  app.add_option("--lobe", o->lobe,
                 "radiance_tables / radiance_compressed: the lobe whose table to export "
                 "(default specular_reflection; delta_transmission: the gap table)");
  app.add_flag("--force", o->force, "replace an existing clothbake asset at the output path");
  return [o] {
    const Asset asset = formats::open_valid_asset(o->asset);
    const SectionType type = parse_section(o->section);
    const bool radiance =
        type == SectionType::RadianceRawTables || type == SectionType::RadianceCompressedTables;
    if (!o->lobe.empty() && !radiance)
      throw Error(ExitCode::Usage,
                  "--lobe: only radiance_tables and radiance_compressed are exported per lobe");
    Image image;
    if (radiance) {
      if (o->instance != 0)
        throw Error(ExitCode::Usage,
                    "--instance: radiance tables are selected with --lobe, not --instance");
      // The checksums of the sections open() reads are verified first (exit 3 when corrupt).
      for (uint32_t i = 0; i < asset.section_count(); ++i) {
        SectionInfo s;
        if (!asset.section(i, &s).ok() || s.type != type) continue;
        if (const Status v = reader::verify_section(asset, s); !v.ok())
          throw Error(ExitCode::InvalidAsset, o->asset + ": " + formats::describe(v));
      }
      image = radiance_image(asset, o->asset, type == SectionType::RadianceCompressedTables,
                             o->lobe.empty() ? "specular_reflection" : o->lobe, o->index);
    } else {
      image = section_export_image(asset, *o, type);
    }

    namespace fs = std::filesystem;
    const fs::path output = o->output;
    std::error_code ec;
    if (fs::exists(output) && fs::equivalent(output, o->asset, ec))
      throw_input_error("the output " + o->output + " is the asset being read");
    formats::OutputOptions options;
    options.require_asset_to_replace = false;
    formats::check_output_path(output, options);
    if (fs::exists(output) && formats::looks_like_asset(output) && !o->force)
      throw_input_error(o->output +
                        " is a clothbake asset; refusing to overwrite it with an image (pass "
                        "--force to replace it)");
    render::write_image_atomically(output, image, PixelType::Float32);
    info("wrote " + o->output + " (" + std::to_string(image.width) + " x " +
         std::to_string(image.height) + ", " + std::to_string(image.channels) + " channels)");
    return 0;
  };
}

const bool export_registered = register_command(
    {"export", "Write one section of an asset as an image (EXR) for inspection", setup_export});

}  // namespace
}  // namespace clothbake::cli
