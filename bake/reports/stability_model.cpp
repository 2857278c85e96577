// The model's rows of `report stability` (stability_rows.hpp; docs/hardening.md, "Stability
// report"): quadratures and long-double closed forms against the model's answers.
#include <algorithm>
#include <cmath>
#include <vector>

#include "bake/reports/stability_rows.hpp"
#include "model/cloth_bsdf.hpp"
#include "model/sggx.hpp"
#include "model/sheen.hpp"
#include "model/spongecake.hpp"

namespace clothbake::reports::stability {
namespace {

using Vec3f = model::Vec3<float>;

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

}  // namespace

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

}  // namespace clothbake::reports::stability
