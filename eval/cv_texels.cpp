// The control variate's packed per-texel records (cv_texels.hpp).
#include "eval/cv_texels.hpp"

#include <algorithm>
#include <cmath>

#include "model/asg.hpp"
#include "model/sggx.hpp"

#include "eval/eval_data.hpp"

namespace clothbake::eval {

bool ControlVariateTexels::build(const EvalData& data) noexcept {
  lines_.reset();
  stride_ = rank_ = 0;
  const reader::CompressedRadianceTables& tables = data.specular.compressed;
  if (!tables.is_open() || data.yarns.size() > 65535 || tables.image_count() > 65535 ||
      data.cluster_count() > 256)
    return false;
  const uint32_t n = data.n;
  const uint64_t texels = uint64_t(n) * n;
  const uint32_t rank = data.visibility_rank();
  // The widest cell sets the stride.
  uint32_t max_count = 1;
  {
    double unused[reader::kMaxCompressedRank + 1];
    for (uint64_t t = 0; t < texels; ++t) {
      uint32_t first = 0;
      max_count = std::max(max_count, tables.texel_image_weights_at(t, &first, unused));
    }
  }
  const uint64_t stride =
      (sizeof(Header) + 4 * uint64_t(rank) + 2 * uint64_t(max_count - 1) + 15) / 16 * 16;
  if (!lines_.allocate((texels * stride + 63) / 64, data.allocator)) return false;
  unsigned char* raw = reinterpret_cast<unsigned char*>(lines_.data());
  stride_ = uint32_t(stride);
  rank_ = rank;
  double weights[reader::kMaxCompressedRank + 1];
  for (uint64_t t = 0; t < texels; ++t) {
    unsigned char* record = raw + t * stride;
    std::fill(record, record + stride, static_cast<unsigned char>(0));
    uint32_t first = 0;
    const uint32_t count = tables.texel_image_weights_at(t, &first, weights);
    Header h{};
    h.first_image = uint16_t(count > 0 ? first : 0);
    h.count = uint16_t(count);
    h.label = uint8_t(data.clusters.label_at(t));
    h.yarn = data.maps.yarn_id[t];
    h.gap = data.maps.gap[t];
    for (int c = 0; c < 3; ++c)
      h.colour[c] = data.maps.albedo.data[3 * t + c];
    new (record) Header(h);
    // One array object each (trivial types: no array cookie), read back as arrays.
    if (rank > 0) {
      float* e = new (record + sizeof(Header)) float[rank];
      const float* source = data.basis.coefficients(t);
      for (uint32_t j = 0; j < rank; ++j)
        e[j] = source[j];
    }
    if (max_count > 1) {
      int16_t* q = new (record + sizeof(Header) + 4 * uint64_t(rank)) int16_t[max_count - 1];
      // Stored coefficients are int16 (the reader widens them to double exactly).
      for (uint32_t j = 1; j < count; ++j)
        q[j - 1] = int16_t(weights[j]);
    }
  }
  if (!exact_.allocate(texels, data.allocator)) return false;
  for (uint64_t t = 0; t < texels; ++t) {
    Exact& x = exact_[t];
    const model::AsgParams<double> lobe = data.visibility.lobe_at(t);
    const model::Asg<double> asg = model::asg_from_params(lobe);
    x.axis[0] = float(asg.z.x);
    x.axis[1] = float(asg.z.y);
    x.axis[2] = float(asg.z.z);
    x.rotation[0] = float(std::cos(lobe.rotation));
    x.rotation[1] = float(std::sin(lobe.rotation));
    x.lambda = float(asg.lambda);
    x.mu = float(asg.mu);
    x.amplitude = float(asg.amplitude);
    const float* tangent = data.maps.tangent.data + 3 * t;
    // The tangent as model::FibreSggx takes it (unit; +z where zero or not finite); the
    // roughness is the yarn's (YarnShading::sggx), any value here.
    const model::FibreSggx<double> sggx =
        model::FibreSggx<double>::make(model::Vec3d(tangent[0], tangent[1], tangent[2]), 0.5);
    x.tangent[0] = float(sggx.t.x);
    x.tangent[1] = float(sggx.t.y);
    x.tangent[2] = float(sggx.t.z);
    const double gap = data.maps.gap[t];
    x.gap = float(std::isnan(gap) ? 1.0 : std::clamp(gap, 0.0, 1.0));
    for (int c = 0; c < 3; ++c)
      x.colour[c] = data.maps.albedo.data[3 * t + c];
    x.yarn = data.maps.yarn_id[t];
    const ControlVariateTexels::Header& h = header(t);
    x.cluster = uint8_t(h.count > 0 ? data.image_cluster[h.first_image] : h.label);
    x.padding = 0;
  }
  return true;
}

}  // namespace clothbake::eval
