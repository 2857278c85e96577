// `clothbake report stability` (report_stability.hpp; docs/hardening.md, "Stability report"): the
// rows (the model's: stability_model.cpp; the baked cases': stability_baked.cpp; accumulated by
// stability_rows.hpp), the CSV and JSON documents and the report's files.
#include "bake/reports/report_stability.hpp"

#include <fmt/format.h>
#include <fmt/printf.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "bake/inputs/terminal_text.hpp"
#include "bake/reports/stability_rows.hpp"
#include "common/error.hpp"

namespace clothbake::reports {
namespace {

namespace fs = std::filesystem;

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"') out += '"';
    out += ch == '\n' ? ' ' : ch;
  }
  return out + "\"";
}

nlohmann::json rows_json(const std::vector<StabilityRow>& rows) {
  nlohmann::json out = nlohmann::json::array();
  for (const StabilityRow& r : rows) {
    auto finite_or_null = [](double v) {
      return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
    };
    out.push_back({{"case", r.case_name},
                   {"parameter", r.parameter},
                   {"quantity", r.quantity},
                   {"direct", r.direct},
                   {"n_queries", r.n_queries},
                   {"n_nonfinite", r.n_nonfinite},
                   {"n_negative", r.n_negative},
                   {"max_abs_error", finite_or_null(r.max_abs_error)},
                   {"max_rel_error", finite_or_null(r.max_rel_error)},
                   {"rel_floor", r.rel_floor},
                   {"tolerance", r.tolerance ? nlohmann::json(*r.tolerance) : nlohmann::json()},
                   {"pass", r.pass},
                   {"warnings", r.warnings}});
  }
  return out;
}

}  // namespace

std::string stability_csv(const std::vector<StabilityRow>& rows) {
  std::string out =
      "case,parameter,quantity,n_queries,n_nonfinite,n_negative,max_abs_error,max_rel_error,"
      "tolerance,pass,warnings,direct\n";
  for (const StabilityRow& r : rows) {
    std::string warnings;
    for (const std::string& w : r.warnings)
      warnings += (warnings.empty() ? "" : " | ") + w;
    out += fmt::format("{},{},{},{},{},{},{:.6g},{:.6g},{},{},{},{}\n", csv_field(r.case_name),
                       csv_field(r.parameter), csv_field(r.quantity), r.n_queries, r.n_nonfinite,
                       r.n_negative, r.max_abs_error, r.max_rel_error,
                       r.tolerance ? fmt::format("{:.3g}", *r.tolerance) : std::string(),
                       r.pass ? "yes" : "no", csv_field(warnings), csv_field(r.direct));
  }
  return out;
}

std::vector<StabilityRow> stability_rows(const StabilityOptions& o, const std::string& scratch) {
  stability::Report report(o.perturb_direct);
  if (o.model) stability::model_rows(report);
  if (o.baked) stability::baked_case_rows(report, o, scratch);
  return std::move(report.rows);
}

ReportOutput stability_report(const StabilityOptions& o) {
  const fs::path out(o.output);
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec))
    throw_input_error(o.output + ": exists and is not a directory");
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  const fs::path tmp = parent / (out.filename().string() + ".tmp-report");
  fs::remove_all(tmp, ec);
  if (!fs::create_directories(tmp / "assets", ec) && ec)
    throw_input_error(tmp.string() + ": cannot create: " + ec.message());
  std::vector<StabilityRow> rows;
  try {
    rows = stability_rows(o, (tmp / "assets").string());
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
  fs::remove_all(tmp / "assets", ec);  // the assets are scratch: the report is the rows
  int failed = 0;
  for (const StabilityRow& r : rows)
    failed += r.pass ? 0 : 1;
  nlohmann::json doc;
  doc["report"] = "stability";
  doc["large"] = o.large;
  doc["rows"] = rows_json(rows);
  doc["failed_rows"] = failed;
  const std::string csv = stability_csv(rows);
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream f(tmp / name, std::ios::binary);
    f << text;
    f.close();
    if (!f) {
      fs::remove_all(tmp, ec);
      throw_input_error((tmp / name).string() + ": cannot write");
    }
  };
  write("stability.csv", csv);
  write("stability.json", doc.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
  fs::create_directories(out, ec);
  for (const char* name : {"stability.csv", "stability.json"}) {
    fs::rename(tmp / name, out / name, ec);
    if (ec) throw_input_error((out / name).string() + ": " + ec.message());
  }
  fs::remove_all(tmp, ec);
  ReportOutput result;
  std::string& text = result.summary;
  {
    text +=
        fmt::sprintf("stability report: %zu rows, %d failed; %s/{stability.csv,stability.json}\n",
                     rows.size(), failed, terminal_safe(o.output).c_str());
    for (const StabilityRow& r : rows)
      if (!r.pass)
        text +=
            fmt::sprintf("  FAILED %s %s %s: %llu non-finite, %llu negative, max rel error %.3g\n",
                         r.case_name.c_str(), r.parameter.c_str(), r.quantity.c_str(),
                         static_cast<unsigned long long>(r.n_nonfinite),
                         static_cast<unsigned long long>(r.n_negative), r.max_rel_error);
  }
  if (failed > 0)
    result.failure = fmt::format("report stability: {} row(s) failed (see {})", failed,
                                 (out / "stability.csv").string());
  result.doc = std::move(doc);
  return result;
}

}  // namespace clothbake::reports
