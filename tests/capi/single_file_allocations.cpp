// The single source file (capi/clothbake.cpp, built without exceptions) allocates only through the
// caller's allocator: this program replaces the global operator new and delete, counts every call
// made while the C interface works, and shades an asset with every method the single file has
// over footprints that build every lazily allocated table (whole-tile and block push-forward sums,
// parallax SATs, the reference's dense weight map). It also makes the allocator fail at one of
// its calls a run, for the first calls and then a stride through the rest: each failure is a
// result (never a crash), and every byte handed out comes back. Usage: single_file_allocations
// ASSET.cbk; exit 0 when all holds, 1 with a message.
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <new>

#include "clothbake.h"

namespace {

long global_new_calls = 0;  // operator new calls while counting
bool counting = false;
bool quiet = false;  // no messages for the refusals made on purpose

struct Counts {
  long allocations = 0, releases = 0;
  long fail_at = -1;  // the index of the allocation to refuse (-1: none)
};

void* counted_allocate(void* user, size_t size, size_t alignment) {
  Counts* c = static_cast<Counts*>(user);
  if (c->fail_at >= 0 && c->allocations == c->fail_at) {
    c->fail_at = -1;  // refuse once; later calls succeed (a transient failure)
    return nullptr;
  }
  const size_t rounded = (size + alignment - 1) / alignment * alignment;
  void* p = std::aligned_alloc(alignment, rounded == 0 ? alignment : rounded);
  if (p != nullptr) ++c->allocations;
  return p;
}

void counted_release(void* user, void* pointer) {
  ++static_cast<Counts*>(user)->releases;
  std::free(pointer);
}

bool fail(const char* what, const cb_error& error) {
  if (!quiet) std::fprintf(stderr, "single_file_allocations: %s: %s\n", what, error.message);
  return false;
}

// Opens, shades with every method, samples and closes; true when every call succeeded.
bool shade(const char* path, const cb_allocator& allocator, bool trusted) {
  cb_error error{};
  cb_asset* asset = nullptr;
  if (cb_asset_open_file(path, trusted ? CB_OPEN_TRUSTED : 0u, &allocator, &asset, &error) != CB_OK)
    return fail("open", error);
  bool ok = true;
  const uint32_t methods[] = {CB_METHOD_MULTISCALE, CB_METHOD_BRUTE, CB_METHOD_REFERENCE};
  // A point, a texel, a fraction of a repeat, a repeat and a half, and 3 x 2 repeats.
  const cb_footprint footprints[] = {{0.25, 0.5, 0.25, 0.5},
                                     {0.5, 0.5, 0.51, 0.51},
                                     {0.1, 0.2, 0.45, 0.6},
                                     {0.2, 0.3, 1.7, 1.8},
                                     {0, 0, 3, 2}};
  const double wi[][3] = {{0.3, -0.2, 0.9}, {-0.5, 0.4, 0.6}};
  const double wo[][3] = {{-0.1, 0.3, 0.95}, {0.6, 0.1, 0.5}};
  for (uint32_t method : methods) {
    cb_options options;
    cb_options_default(&options);
    options.method = method;
    options.spp = 4;
    cb_evaluator* evaluator = nullptr;
    if (cb_evaluator_create(asset, &options, &allocator, &evaluator, &error) != CB_OK) {
      ok = fail("evaluator", error);
      continue;
    }
    cb_rng rng;
    cb_rng_seed(&rng, 7);
    for (const cb_footprint& f : footprints)
      for (int d = 0; d < 2; ++d) {
        double rgb[3], pdf = 0;
        if (cb_estimate(evaluator, &f, wi[d], wo[d], CB_LOBES_ALL, &rng, rgb, &error) != CB_OK)
          ok = fail("estimate", error);
        if (cb_direction_pdf(evaluator, &f, wi[d], wo[d], &pdf, &error) != CB_OK)
          ok = fail("pdf", error);
        const double u[3] = {0.4, 0.7, 0.2};
        cb_direction_sample sample;
        if (cb_sample_direction(evaluator, &f, wo[d], u, &sample, &error) != CB_OK)
          ok = fail("sample", error);
      }
    cb_evaluator_destroy(evaluator);
  }
  cb_asset_close(asset);
  return ok;
}

}  // namespace

void* operator new(size_t size) {
  if (counting) ++global_new_calls;
  void* p = std::malloc(size == 0 ? 1 : size);
  if (p == nullptr) std::abort();
  return p;
}
void* operator new[](size_t size) {
  return operator new(size);
}
void* operator new(size_t size, const std::nothrow_t&) noexcept {
  if (counting) ++global_new_calls;
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, size_t) noexcept {
  std::free(p);
}

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: single_file_allocations ASSET.cbk\n");
    return 2;
  }
  bool ok = true;
  for (bool trusted : {false, true}) {
    Counts counts;
    const cb_allocator allocator{counted_allocate, counted_release, &counts};
    counting = true;
    ok = shade(argv[1], allocator, trusted) && ok;
    counting = false;
    std::printf("%s open: %ld allocations through the callback, %ld releases, %ld operator new\n",
                trusted ? "trusted" : "validated", counts.allocations, counts.releases,
                global_new_calls);
    if (global_new_calls != 0 || counts.allocations == 0 || counts.allocations != counts.releases) {
      std::fprintf(stderr,
                   "single_file_allocations: expected every allocation through the "
                   "callback and every one released\n");
      ok = false;
    }
    // Refuse allocations in turn: the first 24 (the objects, the copy, the maps, the tables) and
    // then every (total / 48)-th, so that every kind of table is refused once or more in a few
    // seconds: a result each time, never a crash, and nothing kept.
    const long total = counts.allocations;
    const long stride = total / 48 > 1 ? total / 48 : 1;
    long refused_results = 0, runs = 0;
    quiet = true;
    for (long k = 0; k < total; k += k < 24 ? 1 : stride) {
      ++runs;
      Counts failing;
      failing.fail_at = k;
      const cb_allocator bad{counted_allocate, counted_release, &failing};
      if (!shade(argv[1], bad, trusted)) ++refused_results;
      if (failing.allocations != failing.releases) {
        std::fprintf(stderr, "single_file_allocations: refusing allocation %ld leaked %ld\n", k,
                     failing.allocations - failing.releases);
        ok = false;
      }
    }
    quiet = false;
    std::printf(
        "  refusing %ld of the %ld allocations, one a run: %ld runs reported an error, "
        "no leak\n",
        runs, total, refused_results);
  }
  return ok ? 0 : 1;
}
