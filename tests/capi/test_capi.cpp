// The C interface (capi/clothbake.h): the C99 shading example's value against `clothbake eval`
// with the same arguments and its sample against the C++ evaluator, bit for bit; estimates and
// densities equal to the C++ evaluator's; bad arguments, bad and corrupted assets, trusted opens;
// the caller's allocator (every allocation released).
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "capi/clothbake.h"
#include "eval/evaluator.hpp"
#include "tests/eval/eval_fixtures.hpp"

namespace clothbake::eval {
namespace {

using eval_test::assets;
using test_support::run_clothbake;
namespace detail = test_support::detail;

std::vector<char> bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// The example's pixel and directions (examples/shade_pixel.c).
const cb_footprint kPixel = {0.125, 0.25, 0.625, 0.5};
const double kWi[3] = {-0.3, 0.2, 0.9}, kWo[3] = {0.1, -0.2, 1.0}, kU[3] = {0.3, 0.6, 0.2};

struct Opened {
  cb_asset* asset = nullptr;
  cb_evaluator* evaluator = nullptr;
  ~Opened() {
    cb_evaluator_destroy(evaluator);
    cb_asset_close(asset);
  }
};

// The fixture is the project's own bake: opened trusted (validation is what
// OpenFromMemoryValidatesUnlessTrusted tests; it costs most of a second per open here).
void open_twill(Opened* o, const cb_options* options = nullptr) {
  cb_error error{};
  ASSERT_EQ(cb_asset_open_file(assets().twill.c_str(), CB_OPEN_TRUSTED, nullptr, &o->asset, &error),
            CB_OK)
      << error.message;
  cb_options defaults;
  cb_options_default(&defaults);
  ASSERT_EQ(
      cb_evaluator_create(o->asset, options ? options : &defaults, nullptr, &o->evaluator, &error),
      CB_OK)
      << error.message;
}

// The example prints the estimate `clothbake eval` gives for the same footprint (in texels: tile
// units times the resolution, exact here), directions, seed and samples: the same double, digit for
// digit (%.17g round-trips), since both run the same evaluator on the same bytes. Its sample is
// the C++ evaluator's.
TEST(CInterface, TheShadingExampleAgreesWithEvalBitForBit) {
  const auto run = detail::spawn({SHADE_PIXEL_EXE, assets().twill});
  ASSERT_EQ(run.code, 0) << run.err;
  std::istringstream out(run.out);
  std::string word;
  double value[3], sample[4];
  out >> word >> value[0] >> value[1] >> value[2];
  ASSERT_EQ(word, "value") << run.out;
  out >> word >> sample[0] >> sample[1] >> sample[2] >> sample[3];
  ASSERT_EQ(word, "sample") << run.out;

  Opened o;
  open_twill(&o);
  cb_asset_info info{};
  ASSERT_EQ(cb_asset_get_info(o.asset, &info, nullptr), CB_OK);
  const double n = info.resolution;
  ASSERT_EQ(n, 64);
  auto num = [](double v) {
    std::ostringstream s;
    s.precision(17);
    s << v;
    return s.str();
  };
  const std::string rect = num(kPixel.u0 * n) + "," + num(kPixel.v0 * n) + "," +
                           num(kPixel.u1 * n) + "," + num(kPixel.v1 * n);
  const std::string wi = num(kWi[0]) + "," + num(kWi[1]) + "," + num(kWi[2]);
  const std::string wo = num(kWo[0]) + "," + num(kWo[1]) + "," + num(kWo[2]);
  const auto eval = run_clothbake({"eval", assets().twill, "--rect", rect, "--wi", wi, "--wo", wo,
                                   "--seed", "1", "--spp", "1", "--json"});
  ASSERT_EQ(eval.code, 0) << eval.err;
  const nlohmann::json j = nlohmann::json::parse(eval.out);
  for (int c = 0; c < 3; ++c)
    EXPECT_EQ(value[c], j["value"][c].get<double>()) << c;
  EXPECT_GT(value[0] + value[1] + value[2], 0.0);

  reader::Asset asset;
  ASSERT_TRUE(asset.open_file(assets().twill.c_str()).ok());
  Evaluator evaluator;
  ASSERT_TRUE(evaluator.open(asset).ok());
  Evaluator::DirectionSample s;
  const Footprint f{kPixel.u0 * n, kPixel.v0 * n, kPixel.u1 * n, kPixel.v1 * n};
  ASSERT_TRUE(evaluator.sample_direction(f, kWo, kU[0], kU[1], kU[2], &s).ok());
  ASSERT_TRUE(s.valid);
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(sample[k], s.wi[k]) << k;
  EXPECT_EQ(sample[3], s.pdf);
}

// Estimates, samples and densities through the C interface are the C++ evaluator's, call after
// call (the caller's rng carries the generator's state between calls), for every method.
TEST(CInterface, EstimatesAndDensitiesAreTheEvaluatorsCallAfterCall) {
  for (uint32_t method :
       {CB_METHOD_MULTISCALE, CB_METHOD_MULTISCALE_PAPER, CB_METHOD_BRUTE, CB_METHOD_REFERENCE}) {
    cb_options options;
    cb_options_default(&options);
    options.method = method;
    options.spp = 4;
    Opened o;
    open_twill(&o, &options);
    reader::Asset asset;
    ASSERT_TRUE(asset.open_file(assets().twill.c_str()).ok());
    Evaluator evaluator;
    ASSERT_TRUE(evaluator.open(asset).ok());
    const Method methods[] = {Method::Multiscale, Method::MultiscalePaper, Method::Brute,
                              Method::Reference};
    cb_rng rng;
    cb_rng_seed(&rng, 77);
    Rng cpp(77);
    // A footprint of 1.5 x 1.25 tiles that starts outside the tile (it wraps).
    const cb_footprint wide = {-0.75, 2.5, 0.75, 3.75};
    const Footprint f{-48, 160, 48, 240};
    for (int call = 0; call < 3; ++call) {
      double rgb[3];
      cb_error error{};
      ASSERT_EQ(cb_estimate(o.evaluator, &wide, kWi, kWo, CB_LOBES_ALL, &rng, rgb, &error), CB_OK)
          << error.message;
      Estimate e;
      ASSERT_TRUE(evaluator.estimate(f, kWi, kWo, methods[method], 4, cpp, kAllLobes, &e).ok());
      EXPECT_EQ(rgb[0], e.value.r) << method << " " << call;
      EXPECT_EQ(rgb[1], e.value.g);
      EXPECT_EQ(rgb[2], e.value.b);
    }
    double pdf = -1, expected = -1;
    ASSERT_EQ(cb_direction_pdf(o.evaluator, &wide, kWi, kWo, &pdf, nullptr), CB_OK);
    ASSERT_TRUE(evaluator.direction_pdf(f, kWi, kWo, &expected).ok());
    EXPECT_EQ(pdf, expected);
    EXPECT_GT(pdf, 0.0);
  }
  // One lobe: the specular reflection alone is part of the whole.
  Opened o;
  cb_options options;
  cb_options_default(&options);
  options.method = CB_METHOD_REFERENCE;
  open_twill(&o, &options);
  cb_rng rng;
  cb_rng_seed(&rng, 1);
  double all[3], specular[3];
  ASSERT_EQ(cb_estimate(o.evaluator, &kPixel, kWi, kWo, CB_LOBES_ALL, &rng, all, nullptr), CB_OK);
  ASSERT_EQ(cb_estimate(o.evaluator, &kPixel, kWi, kWo, CB_LOBE_SPECULAR_REFLECTION, &rng, specular,
                        nullptr),
            CB_OK);
  for (int c = 0; c < 3; ++c) {
    EXPECT_GT(specular[c], 0.0);
    EXPECT_LT(specular[c], all[c]);
  }
}

TEST(CInterface, BadArgumentsAreInvalidArgumentWithAMessage) {
  Opened o;
  open_twill(&o);
  cb_rng rng;
  cb_rng_seed(&rng, 1);
  double rgb[3] = {1, 1, 1};
  cb_error error{};
  const cb_footprint backwards = {0.5, 0, 0.25, 1}, nan = {0, 0, NAN, 1};
  const double zero[3] = {0, 0, 0};
  EXPECT_EQ(cb_estimate(o.evaluator, &backwards, kWi, kWo, CB_LOBES_ALL, &rng, rgb, &error),
            CB_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(rgb[0], 0.0);  // cleared on error
  EXPECT_NE(std::strlen(error.message), 0u);
  EXPECT_EQ(cb_estimate(o.evaluator, &nan, kWi, kWo, CB_LOBES_ALL, &rng, rgb, &error),
            CB_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(cb_estimate(o.evaluator, &kPixel, zero, kWo, CB_LOBES_ALL, &rng, rgb, &error),
            CB_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(cb_estimate(o.evaluator, &kPixel, kWi, kWo, 0, &rng, rgb, &error),
            CB_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(cb_estimate(o.evaluator, &kPixel, kWi, kWo, 64, &rng, rgb, &error),
            CB_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(cb_estimate(nullptr, &kPixel, kWi, kWo, CB_LOBES_ALL, &rng, rgb, nullptr),
            CB_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(cb_estimate(o.evaluator, nullptr, kWi, kWo, CB_LOBES_ALL, &rng, rgb, nullptr),
            CB_ERROR_INVALID_ARGUMENT);
  const double nan_u[3] = {0.5, NAN, 0.5};
  cb_direction_sample sample;
  EXPECT_EQ(cb_sample_direction(o.evaluator, &kPixel, kWo, nan_u, &sample, &error),
            CB_ERROR_INVALID_ARGUMENT);
  for (const double bad : {-0.25, 1.0, 3.0}) {  // outside [0, 1): not a uniform sample
    const double u[3] = {0.5, 0.5, bad};
    EXPECT_EQ(cb_sample_direction(o.evaluator, &kPixel, kWo, u, &sample, &error),
              CB_ERROR_INVALID_ARGUMENT)
        << bad;
  }
  const double edge_u[3] = {0.0, 0.0, 0.9999999999999999};  // the interval's ends that belong
  EXPECT_EQ(cb_sample_direction(o.evaluator, &kPixel, kWo, edge_u, &sample, &error), CB_OK);
  cb_options options;
  cb_options_default(&options);
  options.method = 4;
  cb_evaluator* e = nullptr;
  EXPECT_EQ(cb_evaluator_create(o.asset, &options, nullptr, &e, &error), CB_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(e, nullptr);
  cb_options_default(&options);
  options.spp = 0;
  EXPECT_EQ(cb_evaluator_create(o.asset, &options, nullptr, &e, &error), CB_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cb_result_name(CB_ERROR_OUT_OF_PLAN), "CB_ERROR_OUT_OF_PLAN");
  // An asset without the Integral-Radiance tables: the multi-scale method needs them.
  cb_asset* bare = nullptr;
  ASSERT_EQ(cb_asset_open_file(assets().bare.c_str(), CB_OPEN_TRUSTED, nullptr, &bare, &error),
            CB_OK)
      << error.message;
  cb_options_default(&options);
  ASSERT_EQ(cb_evaluator_create(bare, &options, nullptr, &e, &error), CB_OK) << error.message;
  EXPECT_EQ(cb_estimate(e, &kPixel, kWi, kWo, CB_LOBES_ALL, &rng, rgb, &error), CB_ERROR_NOT_FOUND);
  cb_evaluator_destroy(e);
  cb_asset_close(bare);
}

// Opening from memory: a copy by default (the caller's buffer can go at once), borrowed on request
// (8-byte aligned only); bytes that are not an asset, a truncated asset and a corrupted byte are
// INVALID_ASSET naming the check; with CB_OPEN_TRUSTED a corrupted payload byte (whose checksum
// only validation reads) opens.
TEST(CInterface, OpenFromMemoryValidatesUnlessTrusted) {
  const std::vector<char> good = bytes_of(assets().twill);
  ASSERT_GT(good.size(), 4096u);
  cb_error error{};
  cb_asset* asset = nullptr;
  {
    std::vector<char> copy = good;
    ASSERT_EQ(cb_asset_open_memory(copy.data(), copy.size(), 0, nullptr, &asset, &error), CB_OK)
        << error.message;
    std::fill(copy.begin(), copy.end(), 0);  // the asset keeps its own copy
    cb_options options;
    cb_options_default(&options);
    cb_evaluator* e = nullptr;
    ASSERT_EQ(cb_evaluator_create(asset, &options, nullptr, &e, &error), CB_OK) << error.message;
    cb_rng rng;
    cb_rng_seed(&rng, 1);
    double rgb[3];
    EXPECT_EQ(cb_estimate(e, &kPixel, kWi, kWo, CB_LOBES_ALL, &rng, rgb, &error), CB_OK);
    cb_evaluator_destroy(e);
    cb_asset_close(asset);
  }
  // Borrowed: aligned is fine, one byte off is refused.
  std::vector<uint64_t> aligned((good.size() + 15) / 8);
  std::memcpy(aligned.data(), good.data(), good.size());
  ASSERT_EQ(
      cb_asset_open_memory(aligned.data(), good.size(), CB_OPEN_BORROW, nullptr, &asset, &error),
      CB_OK)
      << error.message;
  cb_asset_close(asset);
  std::memmove(reinterpret_cast<char*>(aligned.data()) + 1, good.data(), good.size());
  EXPECT_EQ(cb_asset_open_memory(reinterpret_cast<char*>(aligned.data()) + 1, good.size(),
                                 CB_OPEN_BORROW, nullptr, &asset, &error),
            CB_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(asset, nullptr);
  // Not an asset; truncated.
  const std::string text = "this is not a clothbake asset, just some bytes of text";
  EXPECT_EQ(cb_asset_open_memory(text.data(), text.size(), 0, nullptr, &asset, &error),
            CB_ERROR_INVALID_ASSET);
  EXPECT_NE(std::string(error.message).find("CBK-E"), std::string::npos) << error.message;
  EXPECT_EQ(cb_asset_open_memory(good.data(), good.size() / 2, 0, nullptr, &asset, &error),
            CB_ERROR_INVALID_ASSET);
  // A flipped byte near the end (inside a section's payload): validation finds the checksum.
  std::vector<char> corrupt = good;
  corrupt[corrupt.size() - 100] ^= 0x5a;
  EXPECT_EQ(cb_asset_open_memory(corrupt.data(), corrupt.size(), 0, nullptr, &asset, &error),
            CB_ERROR_INVALID_ASSET);
  EXPECT_NE(std::string(error.message).find("CBK-E"), std::string::npos) << error.message;
  EXPECT_EQ(asset, nullptr);
  ASSERT_EQ(cb_asset_open_memory(corrupt.data(), corrupt.size(), CB_OPEN_TRUSTED, nullptr, &asset,
                                 &error),
            CB_OK)
      << error.message;
  cb_asset_close(asset);
  EXPECT_EQ(cb_asset_open_file("/nonexistent/asset.cbk", 0, nullptr, &asset, &error), CB_ERROR_IO);
  EXPECT_NE(std::string(error.message).find("/nonexistent/asset.cbk"), std::string::npos);
}

// The caller's allocator serves every object of the interface, each released once; a failing one
// is OUT_OF_MEMORY with nothing leaked.
struct CountingAllocator {
  int allocations = 0, releases = 0, fail_after = -1;
  static void* allocate(void* user, size_t size, size_t alignment) {
    auto* self = static_cast<CountingAllocator*>(user);
    if (self->fail_after >= 0 && self->allocations >= self->fail_after) return nullptr;
    ++self->allocations;
    return std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment);
  }
  static void release(void* user, void* pointer) {
    ++static_cast<CountingAllocator*>(user)->releases;
    std::free(pointer);
  }
};

TEST(CInterface, TheCallersAllocatorServesEveryObject) {
  const std::vector<char> good = bytes_of(assets().twill);
  CountingAllocator counts;
  const cb_allocator allocator{CountingAllocator::allocate, CountingAllocator::release, &counts};
  cb_asset* asset = nullptr;
  ASSERT_EQ(
      cb_asset_open_memory(good.data(), good.size(), CB_OPEN_TRUSTED, &allocator, &asset, nullptr),
      CB_OK);
  EXPECT_EQ(counts.allocations, 2);  // the asset and its copy of the bytes
  cb_options options;
  cb_options_default(&options);
  cb_evaluator* e = nullptr;
  ASSERT_EQ(cb_evaluator_create(asset, &options, &allocator, &e, nullptr), CB_OK);
  // The evaluator, the decoded feature maps and tables, the derived sums: all from the callback.
  EXPECT_GT(counts.allocations, 3);
  cb_evaluator_destroy(e);
  cb_asset_close(asset);
  EXPECT_EQ(counts.releases, counts.allocations);
  for (int fail_after : {0, 1}) {
    CountingAllocator failing;
    failing.fail_after = fail_after;
    const cb_allocator bad{CountingAllocator::allocate, CountingAllocator::release, &failing};
    cb_error error{};
    EXPECT_EQ(cb_asset_open_memory(good.data(), good.size(), 0, &bad, &asset, &error),
              CB_ERROR_OUT_OF_MEMORY)
        << fail_after;
    EXPECT_EQ(asset, nullptr);
    EXPECT_EQ(failing.releases, failing.allocations);
  }
}

// The single source file (capi/clothbake.cpp, no exceptions) shades as the libraries do: the
// example linked against it prints the same bytes, digit for digit (%.17g round-trips doubles), on
// an asset as the default bake writes it (the satin fixture). An asset that also keeps the raw
// parallax (--keep-raw, the twill fixture) is another matter: the libraries read the raw depths,
// the single file the compressed ones (docs/integration.md), which differ within the recorded
// quantisation error, so the estimates differ slightly while the sample does not move.
TEST(SingleFile, TheShadingExampleGivesTheLibrariesBytes) {
  const auto library = detail::spawn({SHADE_PIXEL_EXE, assets().satin});
  const auto single = detail::spawn({SHADE_PIXEL_SINGLE_EXE, assets().satin});
  ASSERT_EQ(library.code, 0) << library.err;
  ASSERT_EQ(single.code, 0) << single.err;
  EXPECT_EQ(single.out, library.out);

  const auto library_raw = detail::spawn({SHADE_PIXEL_EXE, assets().twill});
  const auto single_raw = detail::spawn({SHADE_PIXEL_SINGLE_EXE, assets().twill});
  ASSERT_EQ(single_raw.code, 0) << single_raw.err;
  double a[3], b[3];
  std::string word;
  std::istringstream la(library_raw.out), sa(single_raw.out);
  la >> word >> a[0] >> a[1] >> a[2];
  sa >> word >> b[0] >> b[1] >> b[2];
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(b[c], a[c], 0.02 * a[c]) << c;
  EXPECT_EQ(single_raw.out.substr(single_raw.out.find("sample")),
            library_raw.out.substr(library_raw.out.find("sample")));
}

// Every allocation of the single file goes through the caller's allocator (none through operator
// new), every one is released, and refusing any one of them is a result, never a crash or a leak
// (single_file_allocations.cpp says how).
TEST(SingleFile, AllocatesOnlyThroughTheCallersAllocator) {
  const auto run = detail::spawn({SINGLE_FILE_ALLOCATIONS_EXE, assets().twill});
  EXPECT_EQ(run.code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("0 operator new"), std::string::npos) << run.out;
}

}  // namespace
}  // namespace clothbake::eval
