// Study behind the target-mode defaults (docs/compression.md, "Defaults"): one fabric's specular
// tables with stand-in visibility clusters (k-means on folded tangent and yarn), compressed end to
// end with K C-PCA clusters per visibility cluster, rank cap R and target error E; then footprint
// errors of the reader's compressed queries against direct sums of the raw values, and query
// throughput (compressed, and with "raw" also the raw tables).
//
//   cpca_target_study FABRIC.toml RESOLUTION K R E [POWER_ITERATIONS [raw]]
//
// Not part of the product; random footprints and half vectors come from the project's SplitMix64
// (seed 3).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>

#include "bake/inputs/fabric_load.hpp"
#include "benchmarks/compress/stand_in_clusters.hpp"
#include "compress/compressed_set.hpp"
#include "formats/reader/compressed_tables.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "formats/writer/asset_writer.hpp"
#include "model/directions.hpp"
#include "model/splitmix64.hpp"
#include "tables/radiance_fill.hpp"
#include "tables/radiance_sections.hpp"

static double cpu() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

[[noreturn]] static void usage(const char* why) {
  std::fprintf(stderr,
               "cpca_target_study: %s\nusage: cpca_target_study FABRIC.toml RESOLUTION K R E "
               "[POWER_ITERATIONS [raw]]\n",
               why);
  std::exit(1);
}

// A whole-string number in [lo, hi], or exit 1 naming the argument.
static double number_argument(const char* text, const char* name, double lo, double hi) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !(v >= lo && v <= hi)) {
    std::fprintf(stderr, "cpca_target_study: %s must be in [%g, %g], got '%s'\n", name, lo, hi,
                 text);
    std::exit(1);
  }
  return v;
}

static int int_argument(const char* text, const char* name, int lo, int hi) {
  const double v = number_argument(text, name, lo, hi);
  if (v != std::floor(v)) usage((std::string(name) + " must be an integer").c_str());
  return int(v);
}

using namespace clothbake;
using Clock = std::chrono::steady_clock;
static double secs(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

int main(int argc, char** argv) {
  if (argc < 6 || argc > 8) usage("wrong number of arguments");
  if (argc == 8 && std::strcmp(argv[7], "raw") != 0) usage("the last argument must be 'raw'");
  LoadOptions lo;
  lo.resolution = int_argument(argv[2], "RESOLUTION", 8, 1024);
  // Every argument is checked before the (slow) fill.
  compress::CpcaOptions o;
  o.clusters_per_stratum = int_argument(argv[3], "K", 1, compress::kMaxCpcaClustersPerStratum);
  o.rank = int_argument(argv[4], "R", 0, compress::kMaxCpcaRank);
  o.target_error = number_argument(argv[5], "E", 0.0, 1.0);
  if (argc > 6) o.power_iterations = int_argument(argv[6], "POWER_ITERATIONS", 0, 16);
  auto loaded = load_fabric_description(argv[1], lo);
  Fabric& f = loaded.fabric;
  const int n = f.maps.resolution;
  const studies::StandInClusters km = studies::stand_in_clusters(f.maps);
  const std::vector<uint8_t>& labels = km.labels;
  auto in = tables::radiance_inputs(f, labels, km.clusters);
  auto t0 = Clock::now();
  auto data = compress::directional_texels(reader::RadianceTableKind::Specular, in.view, 32);
  std::printf("fill %.2fs\n", secs(t0));
  t0 = Clock::now();
  timespec pc0;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &pc0);
  compress::CompressionStats st;
  auto set = compress::compress_tables(data, o, &st);
  timespec pc1;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &pc1);
  std::printf("cpu %.2fs ", (pc1.tv_sec - pc0.tv_sec) + 1e-9 * (pc1.tv_nsec - pc0.tv_nsec));
  std::printf(
      "compress %.2fs: cells %d images %d rank %d..%d cpca err %.4f stored err %.4f bytes %llu "
      "ratio %.0f\n",
      secs(t0), st.cells, st.images, st.min_rank, st.max_rank, st.cpca_error, st.error,
      (unsigned long long)st.compressed_bytes, st.ratio());
  auto sections = compress::compressed_sections(set);
  auto bytes = formats::serialize_asset(sections);
  reader::Asset asset;
  auto s = asset.open_memory(bytes.data(), bytes.size());
  if (!s.ok()) {
    std::printf("open: %s\n", s.message());
    return 1;
  }
  reader::CompressedRadianceTables tabs;
  t0 = Clock::now();
  s = tabs.open(asset, reader::RadianceTableKind::Specular);
  if (!s.ok()) {
    std::printf("open tables: %s\n", s.message());
    return 1;
  }
  std::printf("reader open %.3fs, decoded %.1f MB\n", secs(t0), tabs.decoded_bytes() / 1e6);
  // footprint errors vs direct double sums of the raw values, random h
  model::SplitMix64 rng(3);
  auto U = [&rng] { return rng.uniform(); };
  const int B = data.bins(), C = data.cluster_count;
  for (int size : {1, 2, 4, 8, 16, 64, 256}) {
    double se = 0, sf = 0, se1 = 0, sf1 = 0;
    int Q = size >= 64 ? 100 : 1000;
    for (int q = 0; q < Q; ++q) {
      double x0 = U() * n, y0 = U() * n;
      int X0 = int(x0), Y0 = int(y0);
      reader::Footprint fp{double(X0), double(Y0), double(X0 + size), double(Y0 + size)};
      double phi = 2 * M_PI * U(), ct = U(), st2 = std::sqrt(1 - ct * ct);
      double h[3] = {st2 * std::cos(phi), st2 * std::sin(phi), ct};
      reader::BinWeights bw;
      reader::radiance_bin_weights(32, h, &bw);
      std::vector<double> got(C), want(C, 0.0);
      tabs.try_query_all(fp, h, got.data());
      for (int y = Y0; y < Y0 + size; ++y)
        for (int x = X0; x < X0 + size; ++x) {
          std::size_t t = std::size_t(y % n) * n + (x % n);
          int c = data.cluster[t];
          if (c == 255) continue;
          for (uint32_t w = 0; w < bw.count; ++w)
            want[c] += bw.weight[w] * data.values[t * B + bw.bin[w]];
        }
      double ga = 0, wa = 0;
      for (int c = 0; c < C; ++c) {
        se += (got[c] - want[c]) * (got[c] - want[c]);
        sf += want[c] * want[c];
        ga += got[c];
        wa += want[c];
      }
      se1 += (ga - wa) * (ga - wa);
      sf1 += wa * wa;
    }
    std::printf("  %d^2: per-cluster %.4f  sum %.4f\n", size, std::sqrt(se / sf),
                std::sqrt(se1 / sf1));
  }
  // throughput
  std::vector<reader::Footprint> fps(100000);
  std::vector<std::array<double, 3>> hs(100000);
  for (int i = 0; i < 100000; ++i) {
    double x0 = U() * n, y0 = U() * n, w = 1 + U() * 8;
    fps[i] = {x0, y0, x0 + w, y0 + w};
    double phi = 2 * M_PI * U(), ct = U(), st2 = std::sqrt(1 - ct * ct);
    hs[i] = {st2 * std::cos(phi), st2 * std::sin(phi), ct};
  }
  std::vector<double> out(C);
  double sink = 0;
  t0 = Clock::now();
  double c0 = cpu();
  for (int i = 0; i < 100000; ++i) {
    tabs.try_query_all(fps[i], hs[i].data(), out.data());
    sink += out[0];
  }
  std::printf("query_all: %.2f M/s wall, %.2f M/s cpu (%g)\n", 0.1 / secs(t0), 0.1 / (cpu() - c0),
              sink);
  if (argc == 8) {
    tables::RadianceOptions ro;
    ro.bins_per_side = 32;
    auto set = tables::build_specular_tables(in.view, ro);
    auto rs = tables::radiance_sections(std::move(set));
    auto rb = formats::serialize_asset(rs);
    rs.clear();
    reader::Asset ra;
    ra.open_memory(rb.data(), rb.size());
    reader::RawRadianceTables raw;
    auto st3 = raw.open(ra, reader::RadianceTableKind::Specular);
    if (!st3.ok()) {
      std::printf("raw: %s\n", st3.message());
      return 1;
    }
    for (int rep = 0; rep < 2; ++rep) {
      t0 = Clock::now();
      c0 = cpu();
      for (int i = 0; i < 100000; ++i) {
        raw.try_query_all(fps[i], hs[i].data(), out.data());
        sink += out[0];
      }
      std::printf("raw query_all: %.2f M/s wall, %.2f M/s cpu (%g)\n", 0.1 / secs(t0),
                  0.1 / (cpu() - c0), sink);
      t0 = Clock::now();
      c0 = cpu();
      for (int i = 0; i < 100000; ++i) {
        tabs.try_query_all(fps[i], hs[i].data(), out.data());
        sink += out[0];
      }
      std::printf("cmp query_all: %.2f M/s wall, %.2f M/s cpu (%g)\n", 0.1 / secs(t0),
                  0.1 / (cpu() - c0), sink);
    }
  }
}
