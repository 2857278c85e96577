// The C interface (clothbake.h) over the reader, the opt-in validator and the evaluator. Every
// entry point is declared noexcept (CB_NOEXCEPT in C++): the libraries below report errors as
// reader::Status, and nothing here throws (the objects are created with placement new, of types
// whose constructors are noexcept, into the caller's allocator's memory).
#include "capi/clothbake.h"

#include <cmath>
#include <cstdint>
#include <cstring>

#include "eval/evaluator.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/reader/scene_plan_sections.hpp"
#include "formats/validate/validate.hpp"

// Each object keeps the allocator it came from, which its reader views (the asset) and derived
// tables (the evaluator) use too.
struct cb_asset {
  clothbake::reader::Asset asset;
  clothbake::model::Allocator allocator{};
  void* copy = nullptr;  // the asset's bytes when copied (open_memory without CB_OPEN_BORROW)
};

struct cb_evaluator {
  clothbake::eval::Evaluator evaluator;
  clothbake::model::Allocator allocator{};
  clothbake::eval::Method method = clothbake::eval::Method::Multiscale;
  uint32_t spp = 1;
  double resolution = 0;  // texels per tile side
};

namespace {

namespace reader = clothbake::reader;
namespace eval = clothbake::eval;

constexpr uint32_t kKnownOpenFlags = CB_OPEN_BORROW | CB_OPEN_TRUSTED;

// The caller's allocator when it gives both functions, else the library's default one.
clothbake::model::Allocator allocator_or_default(const cb_allocator* allocator) {
  if (allocator != nullptr && allocator->allocate != nullptr && allocator->release != nullptr)
    return {allocator->allocate, allocator->release, allocator->user};
  return clothbake::model::default_allocator();
}

// Appends as much of `text` as fits after the NUL-terminated contents of buf[0..size).
void append(char* buf, size_t size, const char* text) {
  size_t at = std::strlen(buf);
  for (; text != nullptr && *text != '\0' && at + 1 < size; ++text)
    buf[at++] = *text;
  buf[at] = '\0';
}

// Writes "prefix: message" into the caller's buffer (when there is one), truncated to fit, and
// returns `result`.
cb_result fail(cb_error* error, cb_result result, const char* prefix, const char* message) {
  if (error != nullptr) {
    error->message[0] = '\0';
    if (prefix != nullptr && prefix[0] != '\0') {
      append(error->message, sizeof error->message, prefix);
      append(error->message, sizeof error->message, ": ");
    }
    append(error->message, sizeof error->message, message);
  }
  return result;
}

cb_result result_of(const reader::Status& status) {
  switch (status.code()) {
    case reader::ErrorCode::Ok:
      return CB_OK;
    case reader::ErrorCode::Io:
      return CB_ERROR_IO;
    case reader::ErrorCode::Unsupported:
      return CB_ERROR_UNSUPPORTED;
    case reader::ErrorCode::NotFound:
      return CB_ERROR_NOT_FOUND;
    case reader::ErrorCode::InvalidArgument:
      return CB_ERROR_INVALID_ARGUMENT;
    case reader::ErrorCode::OutOfPlan:
      return CB_ERROR_OUT_OF_PLAN;
    default:  // NotAnAsset, UnsupportedVersion, Truncated, Corrupt, Malformed, WrongType
      return CB_ERROR_INVALID_ASSET;
  }
}

// A failed status as a result and a message "prefix: CBK-Ennn: message" (the check ID when the
// status has one).
cb_result fail_status(cb_error* error, const reader::Status& status, const char* prefix) {
  if (error != nullptr) {
    fail(error, CB_OK, prefix, "");
    const char* id = status.check_id();
    if (id != nullptr && id[0] != '\0') {
      append(error->message, sizeof error->message, id);
      append(error->message, sizeof error->message, ": ");
    }
    append(error->message, sizeof error->message, status.message());
  }
  return result_of(status);
}

// A cb_asset or cb_evaluator from `allocator`, which it keeps; null without memory.
template <class T>
T* create(const clothbake::model::Allocator& allocator) {
  T* object = clothbake::model::create_object<T>(allocator);
  if (object != nullptr) object->allocator = allocator;
  return object;
}

template <class T>
void destroy(T* object) {
  if (object == nullptr) return;
  const clothbake::model::Allocator allocator = object->allocator;
  clothbake::model::destroy_object(allocator, object);
}

struct FirstFinding {
  char text[256] = {};
  bool any = false;
};

void keep_first_error(void* user, reader::Check check, uint32_t, const char* message) {
  auto* first = static_cast<FirstFinding*>(user);
  if (first->any || reader::is_warning(check)) return;
  first->any = true;
  append(first->text, sizeof first->text, reader::check_id(check));
  append(first->text, sizeof first->text, ": ");
  append(first->text, sizeof first->text, message);
}

// Validation unless trusted; on failure closes nothing (the caller destroys the asset).
cb_result validate(const cb_asset& asset, uint32_t flags, const char* name, cb_error* error) {
  if ((flags & CB_OPEN_TRUSTED) != 0) return CB_OK;
  FirstFinding first;
  const reader::ValidationSummary summary =
      reader::validate_asset(asset.asset, keep_first_error, &first);
  if (summary.errors == 0) return CB_OK;
  return fail(error, CB_ERROR_INVALID_ASSET, name, first.text);
}

// Three numbers in [0, 1) (NaN is not).
bool unit3(const double u[3]) {
  return u != nullptr && u[0] >= 0 && u[0] < 1 && u[1] >= 0 && u[1] < 1 && u[2] >= 0 && u[2] < 1;
}

// The footprint in texels, or false for a NULL or non-finite one (the evaluator checks the rest).
bool texel_footprint(const cb_evaluator* e, const cb_footprint* f, reader::Footprint* out) {
  if (f == nullptr) return false;
  const double n = e->resolution;
  *out = {f->u0 * n, f->v0 * n, f->u1 * n, f->v1 * n};
  return std::isfinite(out->x0) && std::isfinite(out->y0) && std::isfinite(out->x1) &&
         std::isfinite(out->y1);
}

}  // namespace

extern "C" {

const char* cb_result_name(cb_result result) noexcept {
  switch (result) {
    case CB_OK:
      return "CB_OK";
    case CB_ERROR_INVALID_ARGUMENT:
      return "CB_ERROR_INVALID_ARGUMENT";
    case CB_ERROR_IO:
      return "CB_ERROR_IO";
    case CB_ERROR_INVALID_ASSET:
      return "CB_ERROR_INVALID_ASSET";
    case CB_ERROR_NOT_FOUND:
      return "CB_ERROR_NOT_FOUND";
    case CB_ERROR_UNSUPPORTED:
      return "CB_ERROR_UNSUPPORTED";
    case CB_ERROR_OUT_OF_MEMORY:
      return "CB_ERROR_OUT_OF_MEMORY";
    case CB_ERROR_OUT_OF_PLAN:
      return "CB_ERROR_OUT_OF_PLAN";
  }
  return "CB_ERROR_UNKNOWN";
}

cb_result cb_asset_open_memory(const void* bytes, size_t size, uint32_t flags,
                               const cb_allocator* allocator, cb_asset** out,
                               cb_error* error) noexcept {
  if (out != nullptr) *out = nullptr;
  if (bytes == nullptr || out == nullptr)
    return fail(error, CB_ERROR_INVALID_ARGUMENT, "cb_asset_open_memory",
                "bytes and out are required");
  if ((flags & ~kKnownOpenFlags) != 0)
    return fail(error, CB_ERROR_INVALID_ARGUMENT, "cb_asset_open_memory", "unknown flags");
  const bool borrow = (flags & CB_OPEN_BORROW) != 0;
  if (borrow && reinterpret_cast<uintptr_t>(bytes) % 8 != 0)
    return fail(error, CB_ERROR_INVALID_ARGUMENT, "cb_asset_open_memory",
                "a borrowed buffer must start at an 8-byte boundary (CB_OPEN_BORROW)");
  const clothbake::model::Allocator memory = allocator_or_default(allocator);
  cb_asset* asset = create<cb_asset>(memory);
  if (asset == nullptr)
    return fail(error, CB_ERROR_OUT_OF_MEMORY, "cb_asset_open_memory", "cannot allocate the asset");
  asset->asset.set_allocator(&asset->allocator);
  const void* data = bytes;
  if (!borrow) {
    asset->copy = memory.allocate(memory.user, size == 0 ? 8 : size, 8);
    if (asset->copy == nullptr) {
      destroy(asset);
      return fail(error, CB_ERROR_OUT_OF_MEMORY, "cb_asset_open_memory",
                  "cannot allocate the copy of the asset's bytes");
    }
    if (size > 0) std::memcpy(asset->copy, bytes, size);
    data = asset->copy;
  }
  const reader::Status s = asset->asset.open_memory(data, size);
  cb_result r = s.ok() ? validate(*asset, flags, "asset in memory", error)
                       : fail_status(error, s, "asset in memory");
  if (r != CB_OK) {
    cb_asset_close(asset);
    return r;
  }
  *out = asset;
  return CB_OK;
}

cb_result cb_asset_open_file(const char* path, uint32_t flags, const cb_allocator* allocator,
                             cb_asset** out, cb_error* error) noexcept {
  if (out != nullptr) *out = nullptr;
  if (path == nullptr || out == nullptr)
    return fail(error, CB_ERROR_INVALID_ARGUMENT, "cb_asset_open_file",
                "path and out are required");
  if ((flags & ~kKnownOpenFlags) != 0 || (flags & CB_OPEN_BORROW) != 0)
    return fail(error, CB_ERROR_INVALID_ARGUMENT, path,
                "unknown flags (CB_OPEN_BORROW is for cb_asset_open_memory)");
  const clothbake::model::Allocator memory = allocator_or_default(allocator);
  cb_asset* asset = create<cb_asset>(memory);
  if (asset == nullptr)
    return fail(error, CB_ERROR_OUT_OF_MEMORY, path, "cannot allocate the asset");
  asset->asset.set_allocator(&asset->allocator);
  const reader::Status s = asset->asset.open_file(path);
  // The reader's messages name the path already; validation's findings do not.
  const cb_result r = s.ok() ? validate(*asset, flags, path, error) : fail_status(error, s, "");
  if (r != CB_OK) {
    cb_asset_close(asset);
    return r;
  }
  *out = asset;
  return CB_OK;
}

void cb_asset_close(cb_asset* asset) noexcept {
  if (asset == nullptr) return;
  asset->asset = reader::Asset();  // unmaps a file before the copy goes
  void* copy = asset->copy;
  const clothbake::model::Allocator memory = asset->allocator;
  destroy(asset);
  if (copy != nullptr) memory.release(memory.user, copy);
}

cb_result cb_asset_get_info(const cb_asset* asset, cb_asset_info* out, cb_error* error) noexcept {
  if (asset == nullptr || out == nullptr)
    return fail(error, CB_ERROR_INVALID_ARGUMENT, "cb_asset_get_info",
                "asset and out are required");
  *out = cb_asset_info{};
  const reader::FabricInfoRecord* info = nullptr;
  const reader::Status s = reader::read_fabric_info(asset->asset, &info);
  if (!s.ok()) return fail_status(error, s, "cb_asset_get_info");
  out->resolution = info->resolution;
  out->tile_size_mm = info->tile_size_mm;
  reader::ScenePlanRecord plan{};
  bool present = false;
  const reader::Status p = reader::read_scene_plan(asset->asset, &plan, &present);
  if (!p.ok()) {
    *out = cb_asset_info{};
    return fail_status(error, p, "cb_asset_get_info");
  }
  out->scene_planned = present ? 1u : 0u;
  return CB_OK;
}

void cb_options_default(cb_options* options) noexcept {
  if (options == nullptr) return;
  *options = cb_options{};
  options->method = CB_METHOD_MULTISCALE;
  options->spp = 1;
  options->direct_max_side = eval::EvalOptions().direct_max_side;
}

cb_result cb_evaluator_create(const cb_asset* asset, const cb_options* options,
                              const cb_allocator* allocator, cb_evaluator** out,
                              cb_error* error) noexcept {
  if (out != nullptr) *out = nullptr;
  if (asset == nullptr || options == nullptr || out == nullptr)
    return fail(error, CB_ERROR_INVALID_ARGUMENT, "cb_evaluator_create",
                "asset, options and out are required");
  if (options->method > CB_METHOD_REFERENCE || options->tables > 2 || options->sheen > 1 ||
      options->spp == 0 || !(options->direct_max_side >= 0) ||
      !std::isfinite(options->direct_max_side))
    return fail(error, CB_ERROR_INVALID_ARGUMENT, "cb_evaluator_create",
                "options out of range (method 0-3, tables 0-2, sheen 0-1, spp >= 1, "
                "direct_max_side finite and >= 0)");
  eval::EvalOptions eo;
  const eval::TableChoice tables[] = {eval::TableChoice::Auto, eval::TableChoice::Raw,
                                      eval::TableChoice::Compressed};
  eo.tables = tables[options->tables];
  eo.sheen_convention = options->sheen == 0 ? clothbake::model::SheenConvention::Published
                                            : clothbake::model::SheenConvention::Converged;
  eo.direct_max_side = options->direct_max_side;
  const clothbake::model::Allocator memory = allocator_or_default(allocator);
  cb_evaluator* e = create<cb_evaluator>(memory);
  if (e == nullptr)
    return fail(error, CB_ERROR_OUT_OF_MEMORY, "cb_evaluator_create",
                "cannot allocate the evaluator");
  eo.allocator = &e->allocator;
  const eval::Method methods[] = {eval::Method::Multiscale, eval::Method::MultiscalePaper,
                                  eval::Method::Brute, eval::Method::Reference};
  e->method = methods[options->method];
  e->spp = options->spp;
  const reader::Status s = e->evaluator.open(asset->asset, eo);
  if (!s.ok()) {
    destroy(e);
    return fail_status(error, s, "cb_evaluator_create");
  }
  e->resolution = double(e->evaluator.resolution());
  *out = e;
  return CB_OK;
}

void cb_evaluator_destroy(cb_evaluator* evaluator) noexcept {
  destroy(evaluator);
}

void cb_rng_seed(cb_rng* rng, uint64_t seed) noexcept {
  if (rng != nullptr) rng->state = seed;
}

cb_result cb_estimate(const cb_evaluator* evaluator, const cb_footprint* footprint,
                      const double wi[3], const double wo[3], uint32_t lobes, cb_rng* rng,
                      double out_rgb[3], cb_error* error) noexcept {
  if (out_rgb != nullptr) out_rgb[0] = out_rgb[1] = out_rgb[2] = 0;
  reader::Footprint f;
  if (evaluator == nullptr || rng == nullptr || out_rgb == nullptr || wi == nullptr ||
      wo == nullptr || !texel_footprint(evaluator, footprint, &f))
    return fail(error, CB_ERROR_INVALID_ARGUMENT, "cb_estimate",
                "evaluator, a finite footprint, wi, wo, rng and out_rgb are required");
  eval::Rng generator(rng->state);
  eval::Estimate estimate;
  const reader::Status s = evaluator->evaluator.estimate(
      f, wi, wo, evaluator->method, evaluator->spp, generator, lobes, &estimate);
  rng->state = generator.state();
  if (!s.ok()) return fail_status(error, s, "cb_estimate");
  out_rgb[0] = estimate.value.r;
  out_rgb[1] = estimate.value.g;
  out_rgb[2] = estimate.value.b;
  return CB_OK;
}

cb_result cb_sample_direction(const cb_evaluator* evaluator, const cb_footprint* footprint,
                              const double wo[3], const double u[3], cb_direction_sample* out,
                              cb_error* error) noexcept {
  if (out != nullptr) *out = cb_direction_sample{};
  reader::Footprint f;
  if (evaluator == nullptr || out == nullptr || wo == nullptr || !unit3(u) ||
      !texel_footprint(evaluator, footprint, &f))
    return fail(error, CB_ERROR_INVALID_ARGUMENT, "cb_sample_direction",
                "evaluator, a finite footprint, wo, u in [0, 1) and out are required");
  eval::Evaluator::DirectionSample sample;
  const reader::Status s = evaluator->evaluator.sample_direction(f, wo, u[0], u[1], u[2], &sample);
  if (!s.ok()) return fail_status(error, s, "cb_sample_direction");
  out->valid = sample.valid ? 1u : 0u;
  out->is_delta = sample.is_delta ? 1u : 0u;
  for (int k = 0; k < 3; ++k)
    out->wi[k] = sample.wi[k];
  out->pdf = sample.pdf;
  return CB_OK;
}

cb_result cb_direction_pdf(const cb_evaluator* evaluator, const cb_footprint* footprint,
                           const double wi[3], const double wo[3], double* out_pdf,
                           cb_error* error) noexcept {
  if (out_pdf != nullptr) *out_pdf = 0;
  reader::Footprint f;
  if (evaluator == nullptr || out_pdf == nullptr || wi == nullptr || wo == nullptr ||
      !texel_footprint(evaluator, footprint, &f))
    return fail(error, CB_ERROR_INVALID_ARGUMENT, "cb_direction_pdf",
                "evaluator, a finite footprint, wi, wo and out_pdf are required");
  const reader::Status s = evaluator->evaluator.direction_pdf(f, wi, wo, out_pdf);
  if (!s.ok()) return fail_status(error, s, "cb_direction_pdf");
  return CB_OK;
}

}  // extern "C"
