// Per-texel records of the unbiased form's control variate g (docs/evaluator.md, "Unbiased
// multi-scale", "Cost per estimate"), packed so that one evaluation of g reads one record.
//
// g at texel t needs its cluster label, its visibility basis coefficients e_1..e_M, its gap value,
// its colour and yarn (the diffuse lobe) and the compressed specular tables' image weights of its
// cell. Read from the asset's views these are nine arrays at nine unrelated addresses (the label
// map, the basis coefficients, the gap and colour maps, the yarn map, the cell map, the first
// coefficient index and the coefficients), each a cache miss for the cheap samples of g, which
// land at random texels. A record holds the same values, bit for bit (so g and the push-forward
// sums its base is integrated from stay one function), in one record of one to three cache lines:
//
//   offset  type            field
//   0       u16             first_image   the cell's first compressed image (0 without a cell)
//   2       u16             count         images of the cell: rank + 1 (0: the texel has no cell)
//   4       u8              label         the texel's visibility cluster
//   5       u8              (padding)
//   6       u16             yarn          the texel's yarn index
//   8       f32             gap           I(t)
//   12      f32[3]          colour        the albedo map's RGB
//   24      f32[M]          e             the visibility basis coefficients e_1..e_M
//   24+4M   i16[count - 1]  q             the stored coefficients of images first+1 ..
//   first+count-1
//                                         (image `first`, the cell mean, has weight 1)
//
// The stride is 24 + 4M + 2 (max count - 1) rounded up to 16 bytes; the array is 64-byte aligned.
// Internal to the evaluator library (its layout may change; nothing on disk).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "model/memory.hpp"
#include "model/vec.hpp"

namespace clothbake::eval {

struct EvalData;

class ControlVariateTexels {
 public:
  struct Header {
    uint16_t first_image;
    uint16_t count;
    uint8_t label;
    uint8_t padding;
    uint16_t yarn;
    float gap;
    float colour[3];
  };
  static_assert(sizeof(Header) == 24);
  // What g_V, g with the texel's own visibility, fibre distribution and specular albedo, reads at
  // texel t (docs/evaluator.md, "Unbiased multi-scale"): one cache line.
  struct alignas(64) Exact {
    float axis[3];      // the visibility lobe's unit axis z
    float rotation[2];  // cos psi, sin psi (x = cos psi s + sin psi t, (s, t) the axis's basis)
    float lambda, mu, amplitude;
    float tangent[3];  // the fibre tangent, unit (+z where the map's is zero or not finite)
    float gap;         // I(t) clamped to [0, 1], NaN read as 1 (as model::ClothBsdf)
    float colour[3];   // the albedo map's RGB
    uint16_t yarn;     // the texel's yarn index
    uint8_t cluster;   // the cluster whose yarn attenuation scales the specular lobe
    uint8_t padding;

    // V(t, i) at the unit light direction `light` (the mirrored (i_x, i_y, |i_z|)): the lobe
    // through the Duff basis (s, t) of its axis turned by psi, clamped to [0, 1]; no allocation.
    double visibility(const model::Vec3d& light) const noexcept {
      const model::Vec3d z(axis[0], axis[1], axis[2]);
      if (!(dot(light, z) > 0.0)) return 0.0;
      model::Vec3d s, t;
      model::orthonormal_basis(z, s, t);
      const double a = dot(light, s), b = dot(light, t);
      const double vx = rotation[0] * a + rotation[1] * b, vy = rotation[0] * b - rotation[1] * a;
      const double v =
          double(amplitude) * std::exp(-double(lambda) * vx * vx - double(mu) * vy * vy);
      return v > 1.0 ? 1.0 : v;
    }
  };
  static_assert(sizeof(Exact) == 64);

  // Builds the records of every texel from `data`'s open views (the compressed specular tables
  // must be open). Returns false when the arrays cannot be allocated (N^2 * stride() bytes: 9.4 MB
  // for the 256^2 satin, rank 4, widest cell 53 images: 144 bytes a texel; and N^2 * 64 bytes of
  // g_V's records, 4.2 MB at N = 256) or a value does not
  // fit its field (more than 65 535 images or yarns, more than 256 clusters: the reader's own
  // limits are lower). Not thread-safe against readers; call once, before sharing the data.
  bool build(const EvalData& data) noexcept;

  bool empty() const noexcept { return bytes() == nullptr; }
  uint32_t stride() const noexcept { return stride_; }
  uint32_t rank() const noexcept { return rank_; }

  // The record of texel index t (< N^2): its header, then e (rank() floats) and q.
  const Header& header(uint64_t t) const noexcept {
    return *reinterpret_cast<const Header*>(bytes() + t * stride_);
  }
  const float* coefficients(uint64_t t) const noexcept {
    return reinterpret_cast<const float*>(bytes() + t * stride_ + sizeof(Header));
  }
  const int16_t* image_weights(uint64_t t) const noexcept {
    return reinterpret_cast<const int16_t*>(bytes() + t * stride_ + sizeof(Header) +
                                            4 * std::size_t(rank_));
  }
  const void* address(uint64_t t) const noexcept { return bytes() + t * stride_; }
  const Exact& exact(uint64_t t) const noexcept { return exact_[t]; }

 private:
  struct alignas(64) CacheLine {
    unsigned char bytes[64];
  };
  const unsigned char* bytes() const noexcept {
    return reinterpret_cast<const unsigned char*>(lines_.data());
  }
  model::Buffer<CacheLine> lines_;  // the records, from the evaluator's allocator
  model::Buffer<Exact> exact_;      // g_V's records
  uint32_t stride_ = 0, rank_ = 0;
};

}  // namespace clothbake::eval
