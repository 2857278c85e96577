// Study behind the compressed parallax form (docs/compression.md, "Compressed parallax"): one
// asset's raw parallax codes (bake with --keep-raw or --no-compress), compared in three forms:
//
//   parallax_study ASSET pca RANK...     per-texel directional PCA
//   (benchmarks/compress/parallax_pca.hpp) at
//                                        fixed ranks: stored size, offset errors, fit time
//   parallax_study ASSET codes BITS...   codes requantised to BITS bits with a per-direction step,
//                                        zstd -19 size (zstd CLI), errors
//   parallax_study ASSET form            the compressed form (compress/parallax_hierarchy.hpp) at
//                                        the default target through the reader: size, errors,
//                                        open+checksum time,
//                                        first-footprint (SAT build) cost, footprint errors
//                                        against the raw table per size class, query rates
//   parallax_study ASSET sat             raw codes without stored SATs: time to build the SATs
//
// Not part of the product; random texels/footprints from SplitMix64 (seed 3).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "benchmarks/compress/parallax_pca.hpp"
#include "compress/parallax_codes.hpp"
#include "compress/parallax_hierarchy.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/validate/checksums.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/directions.hpp"
#include "model/splitmix64.hpp"
#include "raycast/parallax.hpp"

using namespace clothbake;

static double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr,
                 "usage: parallax_study ASSET (pca RANK... | codes BITS... | form | sat)\n");
    return 2;
  }
  reader::Asset asset;
  reader::Status st = asset.open_file(argv[1]);
  reader::ParallaxView raw;
  if (st.ok()) st = raw.open(asset, reader::ParallaxSource::Raw);
  if (!st.ok()) {
    std::fprintf(stderr, "%s\n", st.message());
    return 1;
  }
  reader::ArrayView<uint16_t> codes;
  (void)asset.array(reader::SectionType::ParallaxTable, 1, &codes);
  const int n = int(raw.resolution()), dirs = int(raw.dirs());
  const std::size_t d = std::size_t(dirs) * dirs, texels = std::size_t(n) * n;
  compress::ParallaxCodes pc{codes.data,
                             n,
                             dirs,
                             raw.info().min_cos,
                             raw.info().depth_scale,
                             raw.info().reference_height,
                             raw.info().max_offset};
  const std::string mode = argv[2];
  std::printf("asset %s: N = %d, %d^2 directions, raw codes %.1f MB + SATs %.1f MB\n", argv[1], n,
              dirs, texels * d * 2 / 1e6, texels * d * 4 / 1e6);
  if (mode == "sat") {
    std::vector<uint32_t> sat(texels * d);
    const double t0 = now();
    raycast::parallax_sat(codes.data, n, int(d), sat.data());
    std::printf("sat: building the %zu SATs at open: %.3f s (1 thread), %.1f MB in memory\n", d,
                now() - t0, sat.size() * 4 / 1e6);
    return 0;
  }
  const model::DirectionGrid<double> grid{dirs, raw.info().min_cos};
  std::vector<double> tan_n(d);
  for (int j = 0; j < dirs; ++j)
    for (int i = 0; i < dirs; ++i) {
      const model::Vec3d o = grid.bin_center(i, j);
      tan_n[std::size_t(grid.bin_index(i, j))] = n * std::sqrt(o.x * o.x + o.y * o.y) / o.z;
    }
  for (int a = 3; a < argc; ++a) {
    const int param = std::atoi(argv[a]);
    if (mode == "codes") {
      // Per direction: step so that the direction's largest offset takes 2^bits - 1 levels.
      const uint32_t levels = (1u << param) - 1;
      std::vector<uint16_t> q(texels * d);
      double sum2 = 0, mx = 0;
      for (std::size_t e = 0; e < d; ++e) {
        uint16_t top = 0;
        for (std::size_t t = 0; t < texels; ++t)
          top = std::max(top, codes.data[e * texels + t]);
        const double step = top ? double(top) / levels : 1.0;
        for (std::size_t t = 0; t < texels; ++t) {
          const double c = codes.data[e * texels + t];
          const double k = std::nearbyint(c / step);
          q[e * texels + t] = uint16_t(k);
          const double err = std::fabs(k * step - c) * raw.info().depth_scale * tan_n[e];
          sum2 += err * err;
          mx = std::max(mx, err);
        }
      }
      const std::string path = "/tmp/parallax_study_codes.bin";
      {
        std::ofstream out(path, std::ios::binary);
        if (param <= 8)
          for (uint16_t v : q) {
            const char c = char(v);
            out.write(&c, 1);
          }
        else
          out.write(reinterpret_cast<const char*>(q.data()), std::streamsize(q.size() * 2));
      }
      const double t0 = now();
      const std::string cmd = "zstd -q -f -19 -T2 " + path + " -o " + path + ".zst";
      if (std::system(cmd.c_str()) != 0) return 1;
      const double tz = now() - t0;
      std::printf(
          "codes %2d bits: zstd -19 %.2f MB (%.1f s), RMS offset error %.4f texel, max "
          "%.3f; SATs at open as for 'sat'\n",
          param, std::filesystem::file_size(path + ".zst") / 1e6, tz,
          std::sqrt(sum2 / double(texels * d)), mx);
      continue;
    }
    compress::ParallaxPcaOptions options;
    options.fixed_rank = param;
    const compress::ParallaxPca packed = compress::fit_parallax_pca(pc, options);
    std::printf(
        "pca rank %3d: %.2f MB, RMS offset error %.4f texel (max %.2f, %.2f%% > 0.25), "
        "fit %.2f s\n",
        packed.rank, packed.payload_bytes() / 1e6, packed.rms_offset_error, packed.max_offset_error,
        100 * packed.share_above_quarter, packed.seconds);
    std::fflush(stdout);
  }
  if (mode != "form") return 0;
  const compress::HierarchicalParallax packed =
      compress::hierarchical_parallax(pc, compress::kDefaultParallaxMaxError);
  std::vector<formats::Section> sections = compress::hierarchical_parallax_sections(packed);
  const auto bytes = formats::serialize_asset(sections);
  reader::Asset small;
  double t0 = now();
  st = small.open_memory(bytes.data(), bytes.size());
  if (st.ok()) st = reader::verify_checksums(small);
  reader::ParallaxView view;
  if (st.ok()) st = view.open(small);
  const double t_open = now() - t0;
  if (!st.ok()) {
    std::fprintf(stderr, "%s\n", st.message());
    return 1;
  }
  t0 = now();
  (void)view.ensure_sat(0);
  const double t_sat = now() - t0;
  model::SplitMix64 rng(3);
  auto uni = [&] { return rng.uniform(); };
  double fsum2[5] = {}, fmax[5] = {};
  const int fsize[5] = {1, 2, 4, 16, 64};
  const int samples = 20000;
  for (int c = 0; c < 5; ++c)
    for (int s = 0; s < samples; ++s) {
      const double x0 = uni() * n, y0 = uni() * n;
      const double v[3] = {uni() * 2 - 1, uni() * 2 - 1, 0.6 + uni()};
      reader::ParallaxSample a, b;
      (void)raw.footprint_depth({x0, y0, x0 + fsize[c], y0 + fsize[c]}, v, &a);
      (void)view.footprint_depth({x0, y0, x0 + fsize[c], y0 + fsize[c]}, v, &b);
      const double e = std::hypot(a.offset[0] - b.offset[0], a.offset[1] - b.offset[1]) * n;
      fsum2[c] += e * e;
      fmax[c] = std::max(fmax[c], e);
    }
  for (uint32_t b = 0; b < d; ++b)
    (void)view.ensure_sat(b);
  const int queries = 4000000;
  std::vector<double> pos(2 * 4096);
  for (double& p : pos)
    p = uni() * n;
  const double v[3] = {0.3, -0.2, 0.9};
  reader::ParallaxSample sample;
  double acc = 0;
  t0 = now();
  for (int i = 0; i < queries; ++i) {
    (void)view.depth(int64_t(pos[2 * (i & 4095)]), int64_t(pos[2 * (i & 4095) + 1]), v, &sample);
    acc += sample.r;
  }
  const double t_texel = now() - t0;
  t0 = now();
  for (int i = 0; i < queries; ++i) {
    const double x0 = pos[2 * (i & 4095)], y0 = pos[2 * (i & 4095) + 1];
    (void)view.footprint_depth({x0, y0, x0 + 6.5, y0 + 6.5}, v, &sample);
    acc += sample.r;
  }
  const double t_fp = now() - t0;
  std::printf(
      "form: %.2f MB (hierarchical), quantise %.2f s; RMS offset error %.4f texel (max "
      "%.3f, %.4f%% > 0.25); open+checksums %.1f ms, first footprint in a direction "
      "+%.2f ms (its SAT)\n",
      packed.payload_bytes() / 1e6, packed.seconds_quantise, packed.rms_offset_error,
      packed.max_offset_error, 100 * packed.share_above_quarter, 1e3 * t_open, 1e3 * t_sat);
  for (int c = 0; c < 5; ++c)
    std::printf("  footprint %2d^2: offset error against raw RMS %.5f, max %.4f texel\n", fsize[c],
                std::sqrt(fsum2[c] / samples), fmax[c]);
  std::printf("  queries (1 thread): texel %.1f M/s, footprint 6.5^2 %.1f M/s (checksum %g)\n",
              queries / t_texel / 1e6, queries / t_fp / 1e6, acc * 0);
  return 0;
}
