// `clothbake report stability` (report_stability.hpp; docs/hardening.md, "Stability report").
#include "bake/reports/report_stability.hpp"

#include <fmt/format.h>
#include <fmt/printf.h>

#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "bake/inputs/map_limits.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "compress/compress_settings.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/visibility_sections.hpp"
#include "formats/writer/valid_asset.hpp"
#include "model/cloth_bsdf.hpp"
#include "model/directions.hpp"
#include "model/parallax.hpp"
#include "model/parameter_ranges.hpp"
#include "model/sggx.hpp"
#include "model/sheen.hpp"
#include "model/splitmix64.hpp"
#include "model/spongecake.hpp"
#include "verify/compressed_verify.hpp"
#include "verify/radiance_verify.hpp"

namespace clothbake::reports {
namespace {

namespace fs = std::filesystem;
using model::Vec3;
using model::Vec3d;
using Vec3f = model::Vec3<float>;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

// The sweeps. Roughness: the accepted range [1e-4, 1] (model/parameter_ranges.hpp), which contains
// the 1e-3 .. 1. Grazing: cos theta down to 1e-6. Thickness: 0 .. +inf (the model's
// range; the fabric loader accepts (0, 1000]).
const std::vector<double> kRoughness = {model::kMinRoughness, 1e-3, 1e-2, 0.1, 0.3, 1.0};
const std::vector<double> kCosines = {1.0, 0.5, 0.1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6};
const std::vector<double> kThickness = {0.0,  1e-12, 1e-6, 1e-3, 0.1,  1.0,
                                        10.0, 1e3,   1e6,  1e12, 1e30, kInf};

std::string num(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return fmt::format("{:g}", v);
}

Vec3d direction(double cos_theta, double phi) {
  const double s = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
  return {s * std::cos(phi), s * std::sin(phi), cos_theta};
}

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

  void add_row(StabilityRow row, const std::vector<Sample>& samples) {
    for (const Sample& s : samples) {
      ++row.n_queries;
      if (!std::isfinite(s.q)) {
        ++row.n_nonfinite;
        continue;
      }
      if (s.nonnegative && s.q < 0) ++row.n_negative;
      if (std::isnan(s.d)) continue;
      const double e = std::abs(s.q - s.d);
      const double rel = e / std::max(std::abs(s.d), row.rel_floor);
      // NaN errors (a non-finite direct value) count as failures through the comparison below.
      if (!(e <= row.max_abs_error)) row.max_abs_error = std::isnan(e) ? kInf : e;
      if (!(rel <= row.max_rel_error)) row.max_rel_error = std::isnan(rel) ? kInf : rel;
    }
    row.pass = row.n_nonfinite == 0 && row.n_negative == 0 &&
               (!row.tolerance || row.max_rel_error <= *row.tolerance);
    rows.push_back(std::move(row));
  }

  // A row whose errors were measured elsewhere (verify/), as relative errors: max_abs_error and
  // max_rel_error are both the largest of them; a non-finite error counts as a non-finite output.
  void add_relative_row(StabilityRow row, const std::vector<double>& errors) {
    for (double e : errors) {
      if (!std::isfinite(e)) {
        ++row.n_nonfinite;
        continue;
      }
      row.max_rel_error = std::max(row.max_rel_error, e);
    }
    row.max_abs_error = row.max_rel_error;
    row.pass = row.n_nonfinite == 0 && (!row.tolerance || row.max_rel_error <= *row.tolerance);
    rows.push_back(std::move(row));
  }

  // Rows of `q`: one per value of each axis its samples sweep.
  void add(const Quantity& q) {
    auto axis = [&](const char* name, const std::vector<double>& values, int Sample::*field) {
      std::map<int, std::vector<Sample>> groups;
      for (const Sample& s : q.samples)
        if (s.*field >= 0) groups[s.*field].push_back(s);
      for (auto& [index, samples] : groups) {
        StabilityRow row = base(q);
        row.parameter = fmt::format("{}={}", name, num(values[std::size_t(index)]));
        add_row(std::move(row), samples);
      }
      return !groups.empty();
    };
    bool any = axis("roughness", kRoughness, &Sample::roughness);
    any |= axis("cos_theta", kCosines, &Sample::cosine);
    any |= axis("thickness", kThickness, &Sample::thickness);
    if (!any) {
      StabilityRow row = base(q);
      row.parameter = "-";
      add_row(std::move(row), q.samples);
    }
  }

  std::vector<StabilityRow> rows;

 private:
  static StabilityRow base(const Quantity& q) {
    StabilityRow row;
    row.case_name = q.case_name;
    row.quantity = q.quantity;
    row.direct = q.direct;
    row.rel_floor = q.rel_floor;
    row.tolerance = q.tolerance;
    return row;
  }
  double perturb_;
};

// ---------------------------------------------------------------------------------------------
// Model

// The integral of D(m) <w, m>^+ over the sphere, by quadrature of the model's D in the fibre
// frame: m = c t + sqrt(1 - c^2) (cos phi e1 + sin phi e2). The azimuthal integral of <w, m>^+ is
// closed (2 (a psi0 + b sin psi0)); the integral over c is a midpoint rule in beta with
// c = k tan(beta), k = sigma / sqrt(1 - sigma^2), which spreads the lobe of width sigma over the
// whole interval (D dc is smooth in beta), or in c itself for sigma >= 0.5.
double projected_area_quadrature(const model::FibreSggx<double>& d, const Vec3d& w) {
  Vec3d e1, e2;
  model::orthonormal_basis(d.t, e1, e2);
  const double wt = dot(w, d.t);
  const double wp = std::sqrt(std::max(0.0, dot(w, w) - wt * wt));
  auto azimuthal = [&](double c) {
    const double a = c * wt, b = std::sqrt(std::max(0.0, 1 - c * c)) * wp;
    if (a >= b) return 2 * kPi * a;
    if (a <= -b) return 0.0;
    const double psi0 = std::acos(std::clamp(-a / b, -1.0, 1.0));
    return 2 * (a * psi0 + b * std::sin(psi0));
  };
  auto density = [&](double c) {
    const Vec3d m = d.t * c + e1 * std::sqrt(std::max(0.0, 1 - c * c));
    return d.D(m);
  };
  const int n = 20000;
  double sum = 0;
  if (d.sigma < 0.5) {
    const double k = d.sigma / std::sqrt(d.one_minus_sigma2);
    const double bmax = std::atan(1 / k);
    const double h = 2 * bmax / n;
    for (int j = 0; j < n; ++j) {
      const double beta = -bmax + (j + 0.5) * h;
      const double c = k * std::tan(beta);
      const double sec = 1 / std::cos(beta);
      sum += density(c) * azimuthal(c) * k * sec * sec * h;
    }
  } else {
    const double h = 2.0 / n;
    for (int j = 0; j < n; ++j) {
      const double c = -1 + (j + 0.5) * h;
      sum += density(c) * azimuthal(c) * h;
    }
  }
  return sum;
}

// SpongeCake closed forms (model/spongecake.hpp) evaluated independently in long double from the
// SGGX matrix itself: D = 1 / (pi sigma (m^T S^-1 m)^2), sigma(w)^2 = w^T S w.
struct LongSggx {
  long double t[3], s;
  long double proj(const Vec3d& w) const {
    const long double c = t[0] * w.x + t[1] * w.y + t[2] * w.z;
    const long double ww = (long double)w.x * w.x + (long double)w.y * w.y + (long double)w.z * w.z;
    return std::sqrt(s * s * c * c + (ww - c * c));
  }
  long double D(const Vec3d& i, const Vec3d& o) const {
    const long double h[3] = {(long double)i.x + o.x, (long double)i.y + o.y,
                              (long double)i.z + o.z};
    const long double hh = h[0] * h[0] + h[1] * h[1] + h[2] * h[2];
    if (hh == 0) return 0;
    const long double c = (t[0] * h[0] + t[1] * h[1] + t[2] * h[2]) / std::sqrt(hh);
    const long double q = c * c / (s * s) + (1 - c * c);
    return 1 / (3.14159265358979323846264338327950288L * s * q * q);
  }
};

double direct_reflection(const LongSggx& g, double T, const Vec3d& i, const Vec3d& o) {
  if (!(T > 0)) return 0;
  const long double iz = std::abs((long double)i.z), oz = std::abs((long double)o.z);
  const long double li = g.proj(i) / iz, lo = g.proj(o) / oz;
  const long double att = std::isinf(T) ? 1.0L : -std::expm1((long double)-T * (li + lo));
  return double(g.D(i, o) * att / (4 * iz * oz * (li + lo)));
}

double direct_transmission(const LongSggx& g, double T, const Vec3d& i, const Vec3d& o) {
  if (!(T > 0) || std::isinf(T)) return 0;
  const long double iz = std::abs((long double)i.z), oz = std::abs((long double)o.z);
  const long double li = g.proj(i) / iz, lo = g.proj(o) / oz;
  const long double lmin = std::min(li, lo), diff = std::abs(li - lo);
  const long double survive = std::exp((long double)-T * lmin);
  // (e^{-T lo} - e^{-T li}) / (li - lo) = e^{-T lmin} (1 - e^{-T diff}) / diff -> T e^{-T lmin}.
  const long double g_ = diff > 0 ? -std::expm1((long double)-T * diff) / diff : (long double)T;
  return double(g.D(i, o) * survive * g_ / (4 * iz * oz));
}

std::vector<Vec3d> tangents() {
  return {Vec3d{1, 0, 0}, normalize(Vec3d{0.3, 0.8, 0.52}), Vec3d{0, 0, 1}};
}

void model_rows(Report& report) {
  // SGGX projected area against the quadrature of D.
  Quantity area("sggx", "projected_area", "quadrature of the model's D(m) <w,m>+ over the sphere");
  area.tolerance = 1e-6;
  for (std::size_t r = 0; r < kRoughness.size(); ++r)
    for (const Vec3d& t : tangents()) {
      const auto d = model::FibreSggx<double>::make(t, kRoughness[r]);
      for (std::size_t c = 0; c < kCosines.size(); ++c)
        for (double phi : {0.0, 1.1}) {
          const Vec3d w = direction(kCosines[c], phi);
          Sample s;
          s.q = d.projected_area(w);
          s.d = report.perturb(projected_area_quadrature(d, w), 1.0);
          s.roughness = int(r), s.cosine = int(c);
          area.samples.push_back(s);
        }
    }
  report.add(area);

  // SpongeCake f_r, f_t against long double; reciprocity.
  Quantity fr("spongecake", "f_r", "closed form in long double from S");
  Quantity ft("spongecake", "f_t", "closed form in long double from S");
  Quantity tr("spongecake", "unscattered_transmittance", "exp(-T Lambda) in long double");
  Quantity rec("spongecake", "reciprocity f(i,o) vs f(o,i)", "f(o,i) of the model");
  fr.tolerance = ft.tolerance = tr.tolerance = 1e-9;
  rec.tolerance = 1e-12;
  // Relative to the value itself; values below 1e-280 (underflow of a product) count absolutely.
  fr.rel_floor = ft.rel_floor = rec.rel_floor = 1e-280;
  tr.rel_floor = 1e-280;
  for (std::size_t r = 0; r < kRoughness.size(); ++r)
    for (const Vec3d& t : tangents()) {
      const auto d = model::FibreSggx<double>::make(t, kRoughness[r]);
      const LongSggx g{{d.t.x, d.t.y, d.t.z}, d.sigma};
      for (std::size_t k = 0; k < kThickness.size(); ++k) {
        const double T = kThickness[k];
        for (std::size_t ci = 0; ci < kCosines.size(); ++ci)
          for (std::size_t co = 0; co < kCosines.size(); co += 1) {
            const Vec3d i = direction(kCosines[ci], 0.3);
            // Specular configurations too: o mirrors i about a normal of the fibre.
            for (const Vec3d& o :
                 {direction(kCosines[co], 2.1), direction(kCosines[co], 0.3 + kPi)}) {
              const Vec3d ob{o.x, o.y, -o.z};
              Sample s;
              s.roughness = int(r), s.thickness = int(k);
              s.cosine = int(std::max(ci, co));  // grazing: the more grazing of the two
              s.q = model::spongecake_reflection(d, T, i, o);
              s.d = report.perturb(direct_reflection(g, T, i, o), 1e-280);
              fr.samples.push_back(s);
              s.q = model::spongecake_transmission(d, T, i, ob);
              s.d = report.perturb(direct_transmission(g, T, i, ob), 1e-280);
              ft.samples.push_back(s);
              s.q = model::spongecake_reflection(d, T, i, o);
              s.d = report.perturb(model::spongecake_reflection(d, T, o, i), 1e-280);
              rec.samples.push_back(s);
              s.q = model::spongecake_transmission(d, T, i, ob);
              s.d = report.perturb(model::spongecake_transmission(d, T, ob, i), 1e-280);
              rec.samples.push_back(s);
            }
          }
        for (std::size_t c = 0; c < kCosines.size(); ++c) {
          const Vec3d w = direction(kCosines[c], 0.7);
          Sample s;
          s.roughness = int(r), s.thickness = int(k), s.cosine = int(c);
          s.q = model::spongecake_unscattered_transmittance(d, T, w);
          const long double lambda = g.proj(w) / std::abs((long double)w.z);
          s.d = report.perturb(T > 0 ? double(std::exp(-(long double)T * lambda)) : 1.0, 1e-280);
          tr.samples.push_back(s);
        }
      }
    }
  report.add(fr);
  report.add(ft);
  report.add(tr);
  report.add(rec);

  // Sheen: albedo by quadrature through the LTC's change of variables against the table's R.
  // Cells of a G x G grid of the cosine lobe's square are mapped by M; the solid angle of a cell
  // after the map is (pi / (G^2 z_o)) |M^-1 w|^3 / a^2 (the LTC Jacobian), so
  //   R = integral f cos dw ~ sum_k f(w_k) z_k (pi / (G^2 z_o,k)) |M^-1 w_k|^3 / a^2.
  Quantity sheen("sheen", "albedo (LTC quadrature vs table R)",
                 "quadrature of sheen_eval cos over the hemisphere");
  Quantity sheen_t("sheen", "T_sheen in [0,1] and lobe finite", "");
  sheen.tolerance = 1e-6;
  sheen.rel_floor = 1e-6;
  for (std::size_t r = 0; r < kRoughness.size(); ++r)
    for (std::size_t c = 0; c < kCosines.size(); ++c) {
      const Vec3d wo = direction(kCosines[c], 0.4);
      const auto ltc = model::sheen_ltc(wo.z, kRoughness[r]);
      const int G = 256;
      double sum = 0;
      for (int a = 0; a < G; ++a)
        for (int b = 0; b < G; ++b) {
          const double u1 = (a + 0.5) / G, u2 = (b + 0.5) / G;
          const Vec3d w = model::sheen_ltc_sample(ltc, wo, u1, u2);
          const double ro = std::sqrt(u1);
          const double zo = std::sqrt(std::max(0.0, 1 - ro * ro));
          // |M^-1 w| in the frame of wo (x along wo's azimuth).
          const double planar = std::hypot(wo.x, wo.y);
          const double cp = planar > 1e-12 ? wo.x / planar : 1,
                       sp = planar > 1e-12 ? wo.y / planar : 0;
          const double x = w.x * cp + w.y * sp, y = -w.x * sp + w.y * cp;
          const double tx = ltc.a * x + ltc.b * w.z, ty = ltc.a * y;
          const double len = std::sqrt(tx * tx + ty * ty + w.z * w.z);
          sum += model::sheen_eval(w, wo, kRoughness[r]) * w.z * (kPi / (double(G) * G * zo)) *
                 len * len * len / (ltc.a * ltc.a);
        }
      Sample s;
      s.roughness = int(r), s.cosine = int(c);
      s.q = model::sheen_albedo(wo.z, kRoughness[r]);
      s.d = report.perturb(sum, 1e-6);
      sheen.samples.push_back(s);
      for (double ci : kCosines) {
        const Vec3d wi = direction(ci, 2.0);
        Sample v;
        v.roughness = int(r), v.cosine = int(c);
        v.q = model::sheen_eval(wi, wo, kRoughness[r]) + model::sheen_pdf(wi, wo, kRoughness[r]);
        sheen_t.samples.push_back(v);
      }
      Sample v;
      v.roughness = int(r), v.cosine = int(c);
      const double albedo = model::sheen_albedo(wo.z, kRoughness[r]);
      v.q = albedo >= 0 && albedo <= 1 ? albedo : NAN;
      sheen_t.samples.push_back(v);
    }
  report.add(sheen);
  report.add(sheen_t);

  // The layered BSDF (Eq. 4): eval, pdf and sampling finite and >= 0, double and float; float
  // against double (reported only: at roughness 1e-4 the half vector's rounding in float moves
  // t.h by more than the lobe's width); reciprocity without sheen (the sheen lobe is not
  // reciprocal, model/sheen.hpp).
  Quantity ev("cloth_bsdf", "eval/pdf/sample (double)", "");
  Quantity evf("cloth_bsdf", "eval (float) vs double", "the same evaluation in double");
  Quantity crec("cloth_bsdf", "reciprocity without sheen", "f(o,i) of the model");
  evf.rel_floor = 1e-30;
  crec.tolerance = 1e-12;
  crec.rel_floor = 1e-280;
  for (std::size_t r = 0; r < kRoughness.size(); ++r)
    for (std::size_t k = 0; k < kThickness.size(); ++k) {
      model::TexelParams<double> p;
      p.tangent = normalize(Vec3d{0.3, 0.8, 0.52});
      p.roughness = kRoughness[r];
      p.optical_thickness = kThickness[k];
      p.gap = 0.75;
      p.sheen_color = model::Rgb<double>(0.5);
      p.sheen_roughness = kRoughness[r];
      const model::ClothBsdf<double> bsdf(p);
      model::TexelParams<double> p0 = p;
      p0.sheen_color = model::Rgb<double>(0.0);
      const model::ClothBsdf<double> bsdf0(p0);
      model::TexelParams<float> pf;
      pf.tangent = Vec3f{float(p.tangent.x), float(p.tangent.y), float(p.tangent.z)};
      pf.roughness = float(p.roughness);
      pf.optical_thickness = float(p.optical_thickness);
      pf.gap = 0.75f;
      pf.sheen_color = model::Rgb<float>(0.5f);
      pf.sheen_roughness = float(p.sheen_roughness);
      const model::ClothBsdf<float> bsdf_f(pf);
      for (std::size_t ci = 0; ci < kCosines.size(); ++ci)
        for (std::size_t co = 0; co < kCosines.size(); ++co)
          for (double side : {1.0, -1.0}) {
            Vec3d i = direction(kCosines[ci], 0.3);
            i.z *= side;
            const Vec3d o = direction(kCosines[co], 2.1);
            Sample s;
            s.roughness = int(r), s.thickness = int(k);
            s.cosine = int(std::max(ci, co));
            const auto f = bsdf.eval(i, o);
            for (double v :
                 {f.total.r, f.total.g, f.total.b, f.delta_transmission.r, bsdf.pdf(i, o)}) {
              s.q = v;
              ev.samples.push_back(s);
            }
            const auto smp = bsdf.sample(o, 0.37, 0.61, 0.23);
            s.q = smp.valid ? smp.weight.max_component() + smp.pdf : 0.0;
            ev.samples.push_back(s);
            const Vec3f fi{float(i.x), float(i.y), float(i.z)},
                fo{float(o.x), float(o.y), float(o.z)};
            const auto ff = bsdf_f.eval(fi, fo);
            s.q = ff.total.r;
            s.d = report.perturb(f.total.r, 1e-30);
            evf.samples.push_back(s);
            const auto sf = bsdf_f.sample(fo, 0.37f, 0.61f, 0.23f);
            s.q = sf.valid ? sf.weight.max_component() + sf.pdf : 0.0f;
            s.d = NAN;
            evf.samples.push_back(s);
            s.q = bsdf0.eval(i, o).total.r;
            s.d = report.perturb(bsdf0.eval(o, i).total.r, 1e-280);
            crec.samples.push_back(s);
          }
    }
  report.add(ev);
  report.add(evf);
  report.add(crec);
}

// ---------------------------------------------------------------------------------------------
// Baked queries

// A fabric whose height depends on u only (h(u) at texel centres), so that the parallax ray of
// every texel can be cast directly along the piecewise-linear profile between texel centres (the
// bake's mesh, raycast/heightfield_scene.hpp, is that profile extruded along v).
Fabric profile_fabric(const std::string& name, int n, const std::function<double(double)>& h,
                      int dirs, int clusters) {
  Fabric f;
  f.name = name;
  f.maps.allocate(n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const std::size_t i = f.maps.index(x, y);
      const double u = (x + 0.5) / n;
      f.maps.height[i] = float(h(u));
      const double slope = (h(u + 0.5 / n) - h(u - 0.5 / n)) * n;  // d height / d u, tile units
      const double len = std::sqrt(1 + slope * slope);
      f.maps.normal[i] = {float(-slope / len), 0.f, float(1 / len)};
      const bool warp = (x / 2) % 2 == 0;
      f.maps.tangent[i] = warp ? clothbake::Vec3f{0.f, 1.f, 0.f} : clothbake::Vec3f{1.f, 0.f, 0.f};
      f.maps.gap[i] = (x % 8 == 7) ? 0.f : 1.f;
      f.maps.yarn_id[i] = warp ? 0 : 1;
      f.maps.albedo[i] = {0.75f, 0.5f, 0.25f};
    }
  YarnMaterial a, b;
  a.name = "warp";
  a.roughness = 0.05;
  b.name = "weft";
  b.roughness = 0.5;
  b.optical_thickness = 1000.0;  // the loader's maximum
  f.yarns = {a, b};
  f.sheen.color = {0.25, 0.25, 0.25};
  f.sheen.roughness = 0.3;
  f.bake.resolution = n;
  f.bake.parallax_dirs = dirs;
  f.bake.visibility_dirs = dirs;
  f.bake.radiance_dirs = dirs;
  f.bake.clusters = clusters;
  f.inputs.push_back({"fabric", name + " (generated by report stability)", "0000000000000000"});
  return f;
}

// r of the parallax stage (raycast/parallax.cpp) for texel x of a u-only profile, cast directly:
// the ray leaves the texel centre at z_max + lift along -o; the surface between texel centres
// k + 1/2 and k + 3/2 (texel units, wrapped) is linear; r = -clamp(z_max - z_hit, 0, range).
double direct_depth(const std::vector<double>& h, int x, const Vec3d& o) {
  const int n = int(h.size());
  const double zmax = *std::max_element(h.begin(), h.end());
  const double zmin = *std::min_element(h.begin(), h.end());
  const double range = zmax - zmin;
  if (range == 0) return 0;
  const double lift = std::max(1e-3 * range, 1e-6);
  const double z0 = zmax + lift;
  auto height_at = [&](double X) {  // X in texel units, centres at k + 0.5
    const double s = X - 0.5;
    const double k = std::floor(s);
    const double f = s - k;
    const int a = model::wrap_texel((long long)k, n), b = model::wrap_texel((long long)k + 1, n);
    return h[std::size_t(a)] + (h[std::size_t(b)] - h[std::size_t(a)]) * f;
  };
  const double vx = -o.x * n;  // dX / ds (texels per unit of ray length in tile units)
  const double vz = -o.z;
  if (std::abs(vx) < 1e-300) return -std::clamp(zmax - height_at(x + 0.5), 0.0, range);
  // March from centre to centre: on each piece z(s) - H(X(s)) is linear in s.
  double s0 = 0, X = x + 0.5;
  const double smax = (z0 - zmin) / o.z + 1;
  while (s0 < smax) {
    const double Xn = vx > 0 ? std::floor(X - 0.5) + 1.5 : std::ceil(X - 0.5) - 0.5;
    const double Xnext = (Xn == X) ? X + (vx > 0 ? 1 : -1) : Xn;
    const double s1 = s0 + (Xnext - X) / vx;
    const double g0 = z0 + vz * s0 - height_at(X);
    const double g1 = z0 + vz * s1 - height_at(Xnext);
    if (g1 <= 0) {
      const double s = g0 <= 0 ? s0 : s0 + (s1 - s0) * g0 / (g0 - g1);
      const double zhit = z0 + vz * s;
      return -std::clamp(zmax - zhit, 0.0, range);
    }
    s0 = s1, X = Xnext;
  }
  return -range;
}

struct BakedCase {
  std::string name, parameter;
  Fabric fabric;
  int footprints = 24;
};

// What a bake left behind for the queries.
struct BakeOutcome {
  std::string path, failure;
  std::vector<std::string> warnings;
  double seconds = 0;
};

std::string case_path(const BakedCase& c, const std::string& scratch) {
  return (fs::path(scratch) / (c.name + "-" + c.parameter + ".cbk")).string();
}

// Bakes `c` in a child process (fork) with a time limit, so that a stage that never returns
// becomes a failed row instead of a hung report (it once did: docs/hardening.md, "The Embree
// hang"), and so that every case starts from a fresh process. The child writes the asset, its
// warnings (PATH.warnings, one a line) and any error (PATH.error), and leaves with _exit. Call
// before this process starts TBB threads.
BakeOutcome bake_in_child(const BakedCase& c, const std::string& scratch, int timeout_seconds) {
  BakeOutcome out;
  out.path = case_path(c, scratch);
  info(fmt::format("report stability: baking {} {} ({}^2)", c.name, c.parameter,
                   c.fabric.maps.resolution));
  std::fflush(nullptr);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid < 0) {
    out.failure = "fork failed";
    return out;
  }
  if (pid == 0) {
    set_quiet(true);
    int code = 0;
    try {
      pipeline::BakeRequest request;
      request.fabric = c.fabric;
      request.output_path = out.path;
      request.force = true;
      compress::CompressRequest keep;
      keep.keep_raw = true;  // the compressed forms a renderer reads, and the raw ones to verify
      request.seeds.put(stages::kCompressSettingsArtifact, keep);
      pipeline::bake(request, stages::bake_stages());
    } catch (const std::exception& e) {
      std::ofstream(out.path + ".error") << e.what();
      code = 1;
    }
    std::ofstream w(out.path + ".warnings");
    for (std::string line : take_warnings()) {
      std::replace(line.begin(), line.end(), '\n', ' ');
      w << line << '\n';
    }
    w.close();
    ::_exit(code);
  }
  int status = 0;
  bool done = false;
  while (!done) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) {
      done = true;
      break;
    }
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (elapsed > timeout_seconds) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      out.failure = fmt::format("bake timed out after {} s (killed)", timeout_seconds);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ifstream w(out.path + ".warnings");
  for (std::string line; std::getline(w, line);)
    if (!line.empty()) out.warnings.push_back(line);
  std::ifstream e(out.path + ".error");
  std::string error((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  if (!error.empty()) out.failure = "bake failed: " + error;
  if (out.failure.empty() && done && !(WIFEXITED(status) && WEXITSTATUS(status) == 0))
    out.failure = "bake process ended abnormally";
  return out;
}

void baked_rows(Report& report, const BakedCase& c, const BakeOutcome& baked) {
  const Fabric& fabric = c.fabric;
  const int n = fabric.maps.resolution;
  std::vector<std::string> warnings = baked.warnings;
  std::optional<reader::Asset> opened;
  std::string failure = baked.failure;
  if (failure.empty()) try {
      opened.emplace(formats::open_valid_asset(baked.path));
    } catch (const Error& e) {
      failure = e.what();
    }
  auto row_of = [&](const std::string& quantity, const std::string& direct) {
    StabilityRow row;
    row.case_name = c.name;
    row.parameter = c.parameter;
    row.quantity = quantity;
    row.direct = direct;
    return row;
  };
  {
    StabilityRow row = row_of("bake + validate", "");
    row.warnings = warnings;
    Sample s;
    s.q = failure.empty() ? 0.0 : NAN;
    if (!failure.empty()) row.warnings.push_back("failed: " + failure);
    report.add_row(std::move(row), {s});
  }
  if (!opened) return;
  const reader::Asset& asset = *opened;

  // Parallax: every texel at every bin centre, raw and compressed, against the direct ray cast;
  // footprint means against direct sums of the per-texel answers.
  std::vector<double> profile(static_cast<std::size_t>(n));
  for (int x = 0; x < n; ++x)
    profile[std::size_t(x)] = double(fabric.maps.height[std::size_t(x)]);
  const double range = *std::max_element(profile.begin(), profile.end()) -
                       *std::min_element(profile.begin(), profile.end());
  for (auto source : {reader::ParallaxSource::Raw, reader::ParallaxSource::Compressed}) {
    const bool raw = source == reader::ParallaxSource::Raw;
    reader::ParallaxView view;
    StabilityRow depth_row = row_of(raw ? "parallax_depth (raw)" : "parallax_depth (compressed)",
                                    "ray cast of the profile between texel centres");
    StabilityRow foot_row =
        row_of(raw ? "parallax_footprint (raw)" : "parallax_footprint (compressed)",
               "area-weighted sum of the per-texel depths");
    const reader::Status st = view.open(asset, source);
    if (!st.ok()) {
      depth_row.warnings.push_back(std::string("parallax view: ") + st.message());
      report.add_row(std::move(depth_row), {Sample{NAN}});
      continue;
    }
    const int dirs = int(view.dirs());
    const model::DirectionGrid<double> grid{dirs, view.info().min_cos};
    double step_max = 0;
    for (int b = 0; b < dirs * dirs; ++b)
      step_max = std::max(step_max, view.depth_step(uint32_t(b)));
    // Per texel: the query quantises r to the bin's step, so the error bound is step / 2 plus the
    // ray caster's float rounding; errors are relative to the relief's range (flat: exactly 0).
    depth_row.rel_floor = foot_row.rel_floor = std::max(range, 1e-300);
    depth_row.tolerance = range > 0 ? (step_max / 2) / range + 1e-5 : 0.0;
    // Footprint means: exact integer SAT sums, then the covered fractions in double. Measured
    // 6e-11 of the relief at 256^2 and 2.8e-9 at 2048^2 (growing with the table, as a cancellation
    // of prefix sums of up to N^2 x 65535 codes would); 1e-7 of the relief is below 1e-4 texel of
    // Eq. 2 offset at 2048^2.
    foot_row.tolerance = range > 0 ? 1e-7 : 0.0;
    std::vector<Sample> depth_samples, foot_samples;
    // The project's generator: the same footprints on every platform and standard library.
    model::SplitMix64 rng(fabric.bake.seed);
    const int rows_checked = std::min(n, 4);  // the profile is constant in v
    for (int j = 0; j < dirs; ++j)
      for (int i = 0; i < dirs; ++i) {
        const Vec3d o = grid.bin_center(i, j);
        const double v[3] = {o.x, o.y, o.z};
        for (int y = 0; y < rows_checked; ++y)
          for (int x = 0; x < n; ++x) {
            reader::ParallaxSample ps;
            Sample s;
            s.nonnegative = false;
            if (view.depth(x, y * (n / rows_checked), v, &ps).ok()) {
              s.q = ps.r;
              s.d = report.perturb(direct_depth(profile, x, o), range > 0 ? range : 1.0);
            } else {
              s.q = NAN;
            }
            depth_samples.push_back(s);
          }
        // Footprints: sub-texel, one texel at the far corner, a few sizes, a whole tile, more.
        const int bin = j * dirs + i;
        if ((i + j) % 3 != 0 && n > 64) continue;  // large tables: a third of the directions
        std::vector<reader::Footprint> rects = {{n - 0.3, n - 0.3, n - 0.1, n - 0.05},
                                                {n - 1.0, n - 1.0, double(n), double(n)},
                                                {0, 0, double(n), double(n)},
                                                {-0.5 * n, 0.25, 1.0 * n, 1.5 * n}};
        for (int k = 0; k < c.footprints; ++k) {
          const double side = std::min(double(n), std::pow(2.0, 6 * rng.uniform()) * 0.37);
          const double x0 = (rng.uniform() * 3 - 1) * n, y0 = (rng.uniform() * 3 - 1) * n;
          rects.push_back({x0, y0, x0 + side, y0 + side * (0.5 + rng.uniform())});
        }
        for (const reader::Footprint& rect : rects) {
          reader::ParallaxSample ps;
          Sample s;
          s.nonnegative = false;
          if (!view.footprint_depth(rect, v, &ps).ok()) {
            s.q = NAN;
            foot_samples.push_back(s);
            continue;
          }
          double sum = 0;
          const long long xa = (long long)std::floor(rect.x0), xb = (long long)std::ceil(rect.x1);
          const long long ya = (long long)std::floor(rect.y0), yb = (long long)std::ceil(rect.y1);
          // Sum per column (the depth of a column depends on x only here, but the query does
          // not know that: the direct sum still visits the rows once per distinct wrap).
          for (long long y = ya; y < yb; ++y) {
            const double wy = std::min(rect.y1, double(y + 1)) - std::max(rect.y0, double(y));
            if (wy <= 0) continue;
            double row_sum = 0;
            for (long long x = xa; x < xb; ++x) {
              const double wx = std::min(rect.x1, double(x + 1)) - std::max(rect.x0, double(x));
              if (wx > 0) row_sum += wx * view.bin_depth(uint32_t(bin), x, y);
            }
            sum += wy * row_sum;
          }
          const double area = (rect.x1 - rect.x0) * (rect.y1 - rect.y0);
          s.q = ps.r;
          s.d = report.perturb(sum / area, range > 0 ? range : 1.0);
          foot_samples.push_back(s);
        }
      }
    report.add_row(std::move(depth_row), depth_samples);
    report.add_row(std::move(foot_row), foot_samples);
  }

  // Visibility: finite, in [0, 1]; on the flat field 1 wherever the light is above the horizon
  // (nothing occludes), measured against that.
  {
    reader::VisibilityAsgView view;
    const bool flat = range == 0;
    StabilityRow row =
        row_of("visibility (finite, in [0,1])", flat ? "1 (a flat field occludes nothing)" : "");
    std::vector<Sample> samples;
    if (!view.open(asset).ok()) {
      samples.push_back(Sample{NAN});
    } else {
      const int step = std::max(1, n / 16);
      for (int y = 0; y < n; y += step)
        for (int x = 0; x < n; x += step)
          for (double ci : kCosines)
            for (double phi : {0.0, 1.3, 3.0, 4.4}) {
              const Vec3d w = direction(ci, phi);
              const double wv[3] = {w.x, w.y, w.z};
              double v = NAN;
              Sample s;
              s.q = view.visibility(x, y, wv, &v).ok() && v >= 0 && v <= 1 ? v : NAN;
              if (flat && ci >= 0.1) s.d = report.perturb(1.0, 1.0);
              samples.push_back(s);
            }
      if (flat) {
        row.tolerance = 0.05;  // the ASG fit of a constant (the fit error the bake reports)
        row.rel_floor = 1;
      }
    }
    report.add_row(std::move(row), samples);
  }

  // Integral-Radiance tables: the raw tables' footprint sums against direct sums of the texels'
  // bin values (verify/radiance_verify.hpp, (a)); the directional error (b) and the compressed
  // tables' footprint error against raw (reported only: they are approximations by design).
  try {
    verify::RadianceVerifyOptions ro;
    ro.samples = n > 64 ? 40 : 140;
    ro.seed = fabric.bake.seed;
    const verify::RadianceVerifyReport rv = verify::verify_radiance(asset, fabric, ro);
    for (const verify::KindReport& k : rv.kinds) {
      StabilityRow sat = row_of("radiance_footprint (raw, " + k.kind + ")",
                                "sum over the covered texels of their bin values (verify)");
      sat.tolerance = ro.max_rel_error;
      std::vector<double> errors;
      for (const verify::ErrorStats& e : k.sat)
        errors.push_back(e.max), sat.n_queries += uint64_t(e.values);
      report.add_relative_row(std::move(sat), errors);
      if (!k.directional.empty()) {
        StabilityRow dir = row_of("radiance_directional (raw, " + k.kind + ")",
                                  "exact sum of I(x) D_x(h) over the covered texels (verify)");
        std::vector<double> de;
        for (const verify::ErrorStats& e : k.directional)
          de.push_back(e.max), dir.n_queries += uint64_t(e.values);
        report.add_relative_row(std::move(dir), de);
      }
    }
    if (verify::has_compressed_tables(asset)) {
      verify::CompressedVerifyOptions co;
      co.samples = n > 64 ? 100 : 400;
      co.seed = fabric.bake.seed;
      co.throughput = false;
      const verify::CompressedVerifyReport cv = verify::verify_compressed(asset, fabric, co);
      for (const verify::CompressedKindReport& k : cv.kinds) {
        StabilityRow row = row_of("radiance_footprint (compressed, " + k.kind + ")",
                                  "the raw tables' footprint sums (verify)");
        std::vector<double> errors;
        for (const verify::FootprintClassError& e : k.classes)
          errors.push_back(e.max_relative), row.n_queries += uint64_t(e.footprints);
        report.add_relative_row(std::move(row), errors);
      }
    }
  } catch (const Error& e) {
    StabilityRow row = row_of("radiance tables", "");
    row.warnings.push_back(e.what());
    report.add_row(std::move(row), {Sample{NAN}});
  }
}

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
  Report report(o.perturb_direct);
  if (o.model) model_rows(report);
  if (o.baked) {
    std::vector<BakedCase> cases;
    cases.push_back({"flat", "height=0",
                     profile_fabric(
                         "flat", 16, [](double) { return 0.0; }, 8, 2)});
    for (double a : {0.01, 0.1, 1.0, 8.0, inputs::kMaxHeightTiles}) {
      const double amp = a;
      cases.push_back(
          {"relief", "amplitude=" + num(a),
           profile_fabric(
               "relief", 16, [amp](double u) { return amp * std::sin(2 * kPi * u); }, 8, 2)});
    }
    const int big = o.large ? 2048 : 256;
    BakedCase table{"table", fmt::format("resolution={}", big),
                    profile_fabric(
                        "table", big, [](double u) { return 0.02 * std::sin(2 * kPi * 3 * u); },
                        o.large ? 4 : 8, o.large ? 1 : 2)};
    table.footprints = 4;
    if (o.table_case) cases.push_back(std::move(table));
    // Every bake first, each in a child process, before this process runs any TBB code.
    std::vector<BakeOutcome> outcomes;
    for (const BakedCase& c : cases)
      outcomes.push_back(bake_in_child(c, scratch, c.fabric.maps.resolution > 256 ? 3600 : 60));
    for (std::size_t k = 0; k < cases.size(); ++k)
      baked_rows(report, cases[k], outcomes[k]);
  }
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
