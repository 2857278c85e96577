// Internal to `report stability` (report_stability.hpp): the sweeps, the samples of one quantity
// and the Report that turns them into StabilityRows, shared by the model rows
// (stability_model.cpp) and the baked cases (stability_baked.cpp). Not part of the library's API.
#pragma once

#include <cfloat>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "bake/reports/report_stability.hpp"
#include "model/parameter_ranges.hpp"
#include "model/sggx.hpp"

namespace clothbake::reports::stability {

using model::Vec3d;

inline constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr double kPi = 3.14159265358979323846;

// The sweeps. Roughness: the accepted range [1e-4, 1] (model/parameter_ranges.hpp), which contains
// the 1e-3 .. 1. Grazing: cos theta down to 1e-6. Thickness: 0 .. +inf (the model's
// range; the fabric loader accepts (0, 1000]).
inline const std::vector<double> kRoughness = {model::kMinRoughness, 1e-3, 1e-2, 0.1, 0.3, 1.0};
inline const std::vector<double> kCosines = {1.0, 0.5, 0.1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6};
inline const std::vector<double> kThickness = {0.0,  1e-12, 1e-6, 1e-3, 0.1,  1.0,
                                               10.0, 1e3,   1e6,  1e12, 1e30, kInf};

// A sweep value as rows and file names print it: "{:g}", "inf" and "-inf".
std::string num(double v);

// The unit direction at cos theta `cos_theta` and azimuth `phi` (radians).
Vec3d direction(double cos_theta, double phi);

// One comparison: the queried value q, the direct value d (NaN: no direct computation), and the
// sweep indices it belongs to (-1: not swept along that axis).
struct Sample {
  double q = 0, d = NAN;
  bool nonnegative = true;
  int roughness = -1, cosine = -1, thickness = -1;
};

// Samples of one quantity; rows are made per value of each swept axis.
struct Quantity {
  Quantity(std::string c, std::string q, std::string d)
      : case_name(std::move(c)), quantity(std::move(q)), direct(std::move(d)) {}
  std::string case_name, quantity, direct;
  double rel_floor = DBL_MIN;
  std::optional<double> tolerance;
  std::vector<Sample> samples;
};

class Report {
 public:
  explicit Report(double perturb) : perturb_(perturb) {}

  double perturb(double d, double scale) const {
    return perturb_ == 0 ? d : d * (1 + perturb_) + perturb_ * scale;
  }

  void add_row(StabilityRow row, const std::vector<Sample>& samples);

  // A row whose errors were measured elsewhere (verify/), as relative errors: max_abs_error and
  // max_rel_error are both the largest of them; a non-finite error counts as a non-finite output.
  void add_relative_row(StabilityRow row, const std::vector<double>& errors);

  // Rows of `q`: one per value of each axis its samples sweep.
  void add(const Quantity& q);

  std::vector<StabilityRow> rows;

 private:
  static StabilityRow base(const Quantity& q);
  double perturb_;
};

// The model's rows (stability_model.cpp): SGGX, SpongeCake, sheen and the layered BSDF over the
// sweeps, against their direct computations.
void model_rows(Report& report);

// The baked cases' rows (stability_baked.cpp): every case of `options` (flat, reliefs, the table
// case unless options.table_case is false) baked into `scratch`, each in a child process, then
// queried. Call before this process starts TBB threads.
void baked_case_rows(Report& report, const StabilityOptions& options, const std::string& scratch);

}  // namespace clothbake::reports::stability
