// libFuzzer harness for the C interface (capi/clothbake.h) on untrusted bytes: whatever the bytes,
// cb_asset_open_memory (validated, the default) opens them or refuses them with a result and a
// message; an opened asset gives an evaluator or a refusal; every estimate, sample and density
// over it is a result, with finite, non-negative values where it succeeds. Built with
// -fsanitize=fuzzer,address,undefined (tests/fuzz/CMakeLists.txt).
//
// The first byte selects: bit 0, repair; bit 1, a trusted open; bits 2-3, the method (multiscale,
// multiscale-paper, brute, reference: one evaluator an input, which keeps an execution to one
// evaluator's creation and lets the fuzzer choose). An input whose first byte is odd
// is first repaired as an adversary who knows the format would
// repair it: if the structure opens, every section checksum and the header checksum are
// recomputed, so that the mutation reaches validation's value checks and the evaluator instead of
// stopping at a checksum (the rest of the input is the asset).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>

#include "capi/clothbake.h"
#include "formats/reader/asset.hpp"
#include "formats/reader/layout.hpp"
#include "formats/validate/xxh64.hpp"

namespace {

using namespace clothbake::reader;

// Recomputes every checksum of the asset in `bytes` (when its structure opens).
void repair_checksums(unsigned char* bytes, size_t size) {
  Asset asset;
  if (!asset.open_memory(bytes, size).ok()) return;
  FileHeader header;
  std::memcpy(&header, bytes, sizeof header);
  const size_t table = sizeof(FileHeader), entry = header.section_entry_size;
  for (uint32_t i = 0; i < asset.section_count(); ++i) {
    SectionInfo info;
    if (!asset.section(i, &info).ok()) return;
    unsigned char* at = bytes + table + size_t(i) * entry;
    SectionEntry e;
    std::memcpy(&e, at, sizeof e);
    e.checksum = xxh64(bytes + e.offset, size_t(e.stored_size));
    std::memcpy(at, &e, sizeof e);
  }
  // The header checksum: bytes [0, 56) and the whole table, as one stream.
  const size_t table_bytes = size_t(header.section_count) * entry;
  std::unique_ptr<unsigned char[]> stream(new unsigned char[kHeaderChecksumOffset + table_bytes]);
  std::memcpy(stream.get(), bytes, kHeaderChecksumOffset);
  std::memcpy(stream.get() + kHeaderChecksumOffset, bytes + table, table_bytes);
  header.header_checksum = xxh64(stream.get(), kHeaderChecksumOffset + table_bytes);
  std::memcpy(bytes + kHeaderChecksumOffset, &header.header_checksum, 8);
}

// A successful estimate is finite, and non-negative except for the unbiased multi-scale form (its
// single estimates are not clamped).
void check_rgb(const double rgb[3], bool may_be_negative) {
  for (int c = 0; c < 3; ++c)
    if (!std::isfinite(rgb[c]) || (!may_be_negative && rgb[c] < 0)) __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const bool repair = (data[0] & 1) != 0;
  // Bit 1: open trusted (CB_OPEN_TRUSTED: no validation), so that damaged values reach the
  // evaluator's own checks; its contract: a result or wrong values, never an out-of-bounds read.
  const uint32_t flags = CB_OPEN_BORROW | ((data[0] & 2) != 0 ? CB_OPEN_TRUSTED : 0u);
  const uint32_t methods[] = {CB_METHOD_MULTISCALE, CB_METHOD_MULTISCALE_PAPER, CB_METHOD_BRUTE,
                              CB_METHOD_REFERENCE};
  const uint32_t method = methods[(data[0] >> 2) & 3];
  ++data, --size;
  // An exact-size, 8-byte aligned copy (operator new[]), so that AddressSanitizer sees any read
  // past `size`.
  std::unique_ptr<unsigned char[]> copy(new unsigned char[size ? size : 1]);
  if (size) std::memcpy(copy.get(), data, size);
  if (repair) repair_checksums(copy.get(), size);

  cb_error error;
  cb_asset* asset = nullptr;
  const cb_result opened = cb_asset_open_memory(copy.get(), size, flags, nullptr, &asset, &error);
  if (opened != CB_OK) {
    if (asset != nullptr || std::memchr(error.message, 0, sizeof error.message) == nullptr)
      __builtin_trap();
    return 0;
  }
  cb_asset_info info;
  cb_asset_get_info(asset, &info, &error);
  {
    cb_options options;
    cb_options_default(&options);
    options.method = method;
    options.spp = 2;
    cb_evaluator* evaluator = nullptr;
    if (cb_evaluator_create(asset, &options, nullptr, &evaluator, &error) != CB_OK) {
      if (evaluator != nullptr) __builtin_trap();
      cb_asset_close(asset);
      return 0;
    }
    // A point, a sub-texel footprint, a fraction of the tile and several tiles, lit and seen from
    // above, at grazing and from below.
    const cb_footprint footprints[] = {
        {0.3, 0.7, 0.3, 0.7}, {0.5, 0.5, 0.5001, 0.5002}, {-0.2, 0.1, 0.15, 0.4}, {0, 0, 2.5, 1.5}};
    const double wi[][3] = {{-0.3, 0.2, 0.9}, {0.99, 0, 0.01}, {0.1, 0.1, -1}};
    const double wo[3] = {0.1, -0.2, 1.0};
    cb_rng rng;
    cb_rng_seed(&rng, 5);
    for (const cb_footprint& f : footprints) {
      if (method == CB_METHOD_REFERENCE && f.u1 - f.u0 > 1) continue;  // slow, not different
      for (const auto& i : wi) {
        double rgb[3];
        if (cb_estimate(evaluator, &f, i, wo, CB_LOBES_ALL, &rng, rgb, &error) == CB_OK)
          check_rgb(rgb, method == CB_METHOD_MULTISCALE || method == CB_METHOD_MULTISCALE_PAPER);
        double pdf = -1;
        if (cb_direction_pdf(evaluator, &f, i, wo, &pdf, &error) == CB_OK &&
            (!std::isfinite(pdf) || pdf < 0))
          __builtin_trap();
      }
      const double u[3] = {0.3, 0.6, 0.2};
      cb_direction_sample sample;
      if (cb_sample_direction(evaluator, &f, wo, u, &sample, &error) == CB_OK && sample.valid &&
          (!std::isfinite(sample.pdf) || sample.pdf < 0 || !std::isfinite(sample.wi[0])))
        __builtin_trap();
    }
    cb_evaluator_destroy(evaluator);
  }
  cb_asset_close(asset);
  return 0;
}
