// `clothbake report stability -o DIR [--large] [--json]` (docs/hardening.md, "Stability report"):
// the model and the baked queries at the edges of the accepted inputs, each output checked for
// being finite (and non-negative where it must be) and measured against a direct computation of
// the same quantity:
//  - model: fibre SGGX (projected area against a quadrature of D), SpongeCake f_r / f_t (against
//    a long-double evaluation of the closed forms), reciprocity, the sheen lobe (its albedo by
//    quadrature against the table's R), the layered BSDF (eval / pdf / sample, double and float),
//    over roughness 1e-4 ... 1 (the accepted range), cos theta 1 ... 1e-6 and optical thickness
//    0 ... +inf;
//  - baked: small fabrics baked in memory (a flat field, sine reliefs up to the accepted maximum
//    height of +-64 tile widths, one larger table: 256^2 by default, 2048^2 with --large): parallax
//    per texel against a direct ray cast of the same height-field mesh, footprint means against
//    direct sums, visibility in [0, 1] (and 1 on the flat field), the Integral-Radiance tables
//    against direct sums (verify/radiance_verify.hpp), validation of the asset, and every warning
//    the bake issued.
// Writes DIR/stability.csv and DIR/stability.json (through a temporary directory next to DIR,
// moved into place at the end). The command exits 0 when every row passes, 5 (VerificationFailed)
// after writing everything when a row has a non-finite or negative output or an error above its
// tolerance (ReportOutput::failure), 2 for an unwritable output (Error(Input)).
#pragma once

#include "bake/reports/report_output.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace clothbake::reports {

struct StabilityOptions {
  std::string output;
  bool large = false;               // the table case at 2048^2 (else 256^2)
  bool model = true, baked = true;  // which halves to run (tests)
  bool table_case = true;           // the baked table case (256^2 / 2048^2) (tests)
  // Self-check hook (tests): every direct computation d becomes d (1 + perturb) + perturb * s,
  // s the quantity's error scale, so that a report that still passes did not compare anything.
  double perturb_direct = 0.0;
};

struct StabilityRow {
  std::string case_name;  // "sggx", "spongecake", "sheen", "cloth_bsdf", "flat", "relief", ...
  std::string parameter;  // the swept parameter and its value, e.g. "roughness=1e-04"
  std::string quantity;   // what was queried, e.g. "f_r", "parallax_depth"
  std::string direct;     // the direct computation it is measured against ("" if none)
  uint64_t n_queries = 0, n_nonfinite = 0, n_negative = 0;
  double max_abs_error = 0, max_rel_error = 0;  // against `direct` (0 without one)
  double rel_floor = 0;                         // rel = |q - d| / max(|d|, rel_floor)
  std::optional<double> tolerance;              // on max_rel_error; none: reported only
  bool pass = true;                   // finite, non-negative where required, within tolerance
  std::vector<std::string> warnings;  // the bake's warnings (baked cases)
};

// Computes every row (bakes into `scratch`, a directory that exists). Deterministic.
std::vector<StabilityRow> stability_rows(const StabilityOptions& options,
                                         const std::string& scratch);

// The CSV (header + one line per row) and the JSON document of the rows.
std::string stability_csv(const std::vector<StabilityRow>& rows);

// The report: rows, files, the JSON document and the summary.
ReportOutput stability_report(const StabilityOptions& options);

}  // namespace clothbake::reports
