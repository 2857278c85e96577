// clothbake._shading: the C interface (capi/clothbake.h) for Python. Assets and evaluators are thin
// owners of the C objects; estimate / sample / pdf run the C functions over numpy arrays in chunks
// of kChunkSize elements, on worker threads, with the GIL released. The public API and its
// contracts are python/clothbake/__init__.py's (docs/python.md); this file is its engine, and
// checks again what the Python layer checks first (shapes, lengths), so that calling it directly
// cannot read out of bounds.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/unique_ptr.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "capi/clothbake.h"
#include "model/pixel_footprint.hpp"
#include "model/splitmix64.hpp"

namespace nb = nanobind;
using namespace nb::literals;

namespace {

// Elements per chunk: one cb_rng per chunk, so estimates depend on this constant and the seed,
// never on the thread count.
constexpr std::size_t kChunkSize = 256;

// A failed C call. The module's exception translator raises the clothbake.Error subclass of
// `result` (clothbake/_errors.py), carrying cb_result_name(result) and the message.
struct Failure {
  cb_result result;
  std::string message;
};

[[noreturn]] void fail(cb_result result, const std::string& message) {
  throw Failure{result, message};
}

// The generator seed of chunk `chunk` of a call seeded with `seed`: the seed itself for chunk 0
// (so that the first element of a call equals one cb_estimate with cb_rng_seed(seed), as
// `clothbake eval --seed` does), else SplitMix64's finaliser of seed ^ (chunk * golden gamma), a
// state far from every other chunk's stream. Pure.
uint64_t chunk_seed(uint64_t seed, uint64_t chunk) noexcept {
  if (chunk == 0) return seed;
  constexpr uint64_t kGamma = 0x9E3779B97F4A7C15ull;  // splitmix64_next adds it before mixing
  uint64_t state = (seed ^ (chunk * kGamma)) - kGamma;
  return clothbake::model::splitmix64_next(state);
}

// An open asset: owns the cb_asset, closed on destruction (evaluators keep their asset alive).
class Asset {
 public:
  Asset(cb_asset* asset, std::string source) : asset_(asset), source_(std::move(source)) {}
  ~Asset() { cb_asset_close(asset_); }
  Asset(const Asset&) = delete;
  Asset& operator=(const Asset&) = delete;

  const cb_asset* get() const { return asset_; }
  const std::string& source() const { return source_; }

 private:
  cb_asset* asset_;
  std::string source_;
};

// Opens the asset file at `path`, validated unless `trusted` (cb_asset_open_file's contract), with
// the GIL released. Raises the clothbake.Error of the C result (IO, INVALID_ASSET, ...).
std::unique_ptr<Asset> open_file(const std::string& path, bool trusted) {
  cb_asset* asset = nullptr;
  cb_error error{};
  cb_result result;
  {
    nb::gil_scoped_release release;
    result =
        cb_asset_open_file(path.c_str(), trusted ? CB_OPEN_TRUSTED : 0u, nullptr, &asset, &error);
  }
  if (result != CB_OK) fail(result, error.message);
  return std::make_unique<Asset>(asset, path);
}

// Opens an asset from the bytes of `data` (copied: the bytes object may go after the call),
// validated unless `trusted`, with the GIL released (a bytes object is immutable). Errors as
// open_file, IO aside.
std::unique_ptr<Asset> open_memory(const nb::bytes& data, bool trusted) {
  cb_asset* asset = nullptr;
  cb_error error{};
  cb_result result;
  const void* bytes = data.c_str();
  const std::size_t size = data.size();
  {
    nb::gil_scoped_release release;
    result =
        cb_asset_open_memory(bytes, size, trusted ? CB_OPEN_TRUSTED : 0u, nullptr, &asset, &error);
  }
  if (result != CB_OK) fail(result, error.message);
  return std::make_unique<Asset>(asset, "asset in memory");
}

// cb_asset_get_info as (resolution, tile_size_mm, scene_planned). Raises NOT_FOUND or
// INVALID_ASSET for an asset opened trusted whose records are missing or damaged.
nb::tuple asset_info(const Asset& asset) {
  cb_asset_info info{};
  cb_error error{};
  const cb_result result = cb_asset_get_info(asset.get(), &info, &error);
  if (result != CB_OK) fail(result, error.message);
  return nb::make_tuple(info.resolution, info.tile_size_mm, info.scene_planned != 0);
}

using Footprints = nb::ndarray<const double, nb::shape<-1, 4>, nb::c_contig, nb::device::cpu>;
using Vectors = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using OutVectors = nb::ndarray<double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using OutScalars = nb::ndarray<double, nb::shape<-1>, nb::c_contig, nb::device::cpu>;
using OutFlags = nb::ndarray<bool, nb::shape<-1>, nb::c_contig, nb::device::cpu>;

// The first failure of one chunk (the chunk stops there).
struct ChunkFailure {
  std::size_t index = SIZE_MAX;
  cb_result result = CB_OK;
  cb_error error{};
};

// Calls body(chunk, begin, end, failure) for every chunk of [0, n) on up to `threads` threads
// (0: one per hardware thread; never more than the chunks), the GIL released. The body must not
// throw. Afterwards raises the failure with the lowest element index, as "<what>, element I:
// <message>", so that the error does not depend on the thread count either.
template <class Body>
void for_each_chunk(const char* what, std::size_t n, int threads, const Body& body) {
  if (threads < 0) throw nb::value_error("threads must be >= 0 (0: every core)");
  const std::size_t chunks = (n + kChunkSize - 1) / kChunkSize;
  std::vector<ChunkFailure> failures(chunks);
  {
    nb::gil_scoped_release release;
    std::size_t workers = threads > 0
                              ? std::size_t(threads)
                              : std::max<std::size_t>(1, std::thread::hardware_concurrency());
    workers = std::min(workers, chunks);
    std::atomic<std::size_t> next{0};
    const auto work = [&]() noexcept {
      for (std::size_t c; (c = next.fetch_add(1, std::memory_order_relaxed)) < chunks;) {
        const std::size_t begin = c * kChunkSize;
        body(c, begin, std::min(n, begin + kChunkSize), failures[c]);
      }
    };
    std::vector<std::thread> pool;
    for (std::size_t t = 1; t < workers; ++t) {
      try {
        pool.emplace_back(work);
      } catch (const std::system_error&) {
        break;  // no more threads to be had: the ones started and this one do the work
      }
    }
    work();
    for (auto& thread : pool)
      thread.join();
  }
  for (const ChunkFailure& f : failures)
    if (f.result != CB_OK)
      fail(f.result,
           std::string(what) + ", element " + std::to_string(f.index) + ": " + f.error.message);
}

void check_rows(const char* name, std::size_t rows, std::size_t n) {
  if (rows != n)
    throw nb::value_error((std::string(name) + " has " + std::to_string(rows) +
                           " rows, footprints has " + std::to_string(n))
                              .c_str());
}

cb_footprint footprint_at(const double* f, std::size_t i) {
  return cb_footprint{f[4 * i], f[4 * i + 1], f[4 * i + 2], f[4 * i + 3]};
}

using Pairs = nb::ndarray<const double, nb::shape<-1, 2>, nb::c_contig, nb::device::cpu>;
using OutFootprints = nb::ndarray<double, nb::shape<-1, 4>, nb::c_contig, nb::device::cpu>;

// out[i] = model::pixel_footprint(uv[i] * scale, (duv_dx[i], duv_dy[i]), scale, max_side): the
// footprint rule of clothbake's renderer (docs/rendering.md, "Pixel footprints") for rows of
// surface coordinates and their per-pixel derivatives. Pure; the GIL is held (a few ns a row).
void pixel_footprints(const Pairs& uv, const Pairs& duv_dx, const Pairs& duv_dy, double scale,
                      double max_side, OutFootprints& out) {
  const std::size_t n = uv.shape(0);
  if (duv_dx.shape(0) != n || duv_dy.shape(0) != n || out.shape(0) != n)
    throw nb::value_error("uv, duv_dx, duv_dy and out must have the same number of rows");
  const double *p = uv.data(), *dx = duv_dx.data(), *dy = duv_dy.data();
  double* f = out.data();
  for (std::size_t i = 0; i < n; ++i) {
    const clothbake::model::UvDifferentials d{dx[2 * i], dx[2 * i + 1], dy[2 * i], dy[2 * i + 1]};
    const clothbake::model::FootprintRectangle r = clothbake::model::pixel_footprint(
        p[2 * i] * scale, p[2 * i + 1] * scale, d, scale, max_side);
    f[4 * i] = r.u0;
    f[4 * i + 1] = r.v0;
    f[4 * i + 2] = r.u1;
    f[4 * i + 3] = r.v1;
  }
}

using Scalars = nb::ndarray<const double, nb::shape<-1>, nb::c_contig, nb::device::cpu>;
using OutPairs = nb::ndarray<double, nb::shape<-1, 2>, nb::c_contig, nb::device::cpu>;

// Row i: model::uv_differentials(t[i], direction[i], ddx[i], ddy[i], normal[i], dpdu[i], dpdv[i])
// into out_dx[i] = (du/dx, dv/dx) and out_dy[i] = (du/dy, dv/dy). Pure; the GIL is held.
void uv_differentials(const Scalars& t, const Vectors& direction, const Vectors& ddx,
                      const Vectors& ddy, const Vectors& normal, const Vectors& dpdu,
                      const Vectors& dpdv, OutPairs& out_dx, OutPairs& out_dy) {
  const std::size_t n = t.shape(0);
  for (const std::size_t rows : {direction.shape(0), ddx.shape(0), ddy.shape(0), normal.shape(0),
                                 dpdu.shape(0), dpdv.shape(0), out_dx.shape(0), out_dy.shape(0)})
    if (rows != n) throw nb::value_error("every row array must have as many rows as t");
  using clothbake::model::Vec3d;
  const auto row = [](const Vectors& a, std::size_t i) {
    const double* p = a.data() + 3 * i;
    return Vec3d(p[0], p[1], p[2]);
  };
  for (std::size_t i = 0; i < n; ++i) {
    const clothbake::model::UvDifferentials d =
        clothbake::model::uv_differentials(t.data()[i], row(direction, i), row(ddx, i), row(ddy, i),
                                           row(normal, i), row(dpdu, i), row(dpdv, i));
    out_dx.data()[2 * i] = d.du_dx;
    out_dx.data()[2 * i + 1] = d.dv_dx;
    out_dy.data()[2 * i] = d.du_dy;
    out_dy.data()[2 * i + 1] = d.dv_dy;
  }
}

// An evaluator over an asset (which the binding keeps alive as long as the evaluator).
class Evaluator {
 public:
  // cb_evaluator_create with the given cb_options fields, the GIL released. Raises the C result's
  // error (INVALID_ARGUMENT for an option out of range, NOT_FOUND for missing tables, ...).
  Evaluator(const Asset& asset, uint32_t method, uint32_t tables, uint32_t sheen, uint32_t spp,
            double direct_max_side) {
    cb_options options;
    cb_options_default(&options);
    options.method = method;
    options.tables = tables;
    options.sheen = sheen;
    options.spp = spp;
    options.direct_max_side = direct_max_side;
    cb_error error{};
    cb_result result;
    {
      nb::gil_scoped_release release;
      result = cb_evaluator_create(asset.get(), &options, nullptr, &evaluator_, &error);
    }
    if (result != CB_OK) fail(result, error.message);
  }
  ~Evaluator() { cb_evaluator_destroy(evaluator_); }
  Evaluator(const Evaluator&) = delete;
  Evaluator& operator=(const Evaluator&) = delete;

  // out[i] = cb_estimate(footprints[i], wi[i], wo[i], lobes) with chunk c's generator seeded
  // chunk_seed(seed, c) and advanced element by element within the chunk.
  void estimate(const Footprints& footprints, const Vectors& wi, const Vectors& wo, uint32_t lobes,
                uint64_t seed, int threads, OutVectors& out) const {
    const std::size_t n = footprints.shape(0);
    check_rows("wi", wi.shape(0), n);
    check_rows("wo", wo.shape(0), n);
    check_rows("out", out.shape(0), n);
    const double* f = footprints.data();
    const double* in = wi.data();
    const double* view = wo.data();
    double* rgb = out.data();
    const cb_evaluator* evaluator = evaluator_;
    for_each_chunk(
        "estimate", n, threads,
        [&](std::size_t chunk, std::size_t begin, std::size_t end, ChunkFailure& failure) {
          cb_rng rng;
          cb_rng_seed(&rng, chunk_seed(seed, chunk));
          for (std::size_t i = begin; i < end; ++i) {
            const cb_footprint fp = footprint_at(f, i);
            const cb_result r = cb_estimate(evaluator, &fp, in + 3 * i, view + 3 * i, lobes, &rng,
                                            rgb + 3 * i, &failure.error);
            if (r != CB_OK) {
              failure.index = i;
              failure.result = r;
              return;
            }
          }
        });
  }

  // cb_sample_direction per element into out_wi, out_pdf, out_valid, out_delta.
  void sample(const Footprints& footprints, const Vectors& wo, const Vectors& u, int threads,
              OutVectors& out_wi, OutScalars& out_pdf, OutFlags& out_valid,
              OutFlags& out_delta) const {
    const std::size_t n = footprints.shape(0);
    check_rows("wo", wo.shape(0), n);
    check_rows("u", u.shape(0), n);
    check_rows("out_wi", out_wi.shape(0), n);
    check_rows("out_pdf", out_pdf.shape(0), n);
    check_rows("out_valid", out_valid.shape(0), n);
    check_rows("out_delta", out_delta.shape(0), n);
    const double* f = footprints.data();
    const double* view = wo.data();
    const double* random = u.data();
    double* wi = out_wi.data();
    double* pdf = out_pdf.data();
    bool* valid = out_valid.data();
    bool* delta = out_delta.data();
    const cb_evaluator* evaluator = evaluator_;
    for_each_chunk("sample", n, threads,
                   [&](std::size_t, std::size_t begin, std::size_t end, ChunkFailure& failure) {
                     for (std::size_t i = begin; i < end; ++i) {
                       const cb_footprint fp = footprint_at(f, i);
                       cb_direction_sample s{};
                       const cb_result r = cb_sample_direction(evaluator, &fp, view + 3 * i,
                                                               random + 3 * i, &s, &failure.error);
                       if (r != CB_OK) {
                         failure.index = i;
                         failure.result = r;
                         return;
                       }
                       for (int k = 0; k < 3; ++k)
                         wi[3 * i + k] = s.wi[k];
                       pdf[i] = s.pdf;
                       valid[i] = s.valid != 0;
                       delta[i] = s.is_delta != 0;
                     }
                   });
  }

  // out[i] = cb_direction_pdf(footprints[i], wi[i], wo[i]).
  void pdf(const Footprints& footprints, const Vectors& wi, const Vectors& wo, int threads,
           OutScalars& out) const {
    const std::size_t n = footprints.shape(0);
    check_rows("wi", wi.shape(0), n);
    check_rows("wo", wo.shape(0), n);
    check_rows("out", out.shape(0), n);
    const double* f = footprints.data();
    const double* in = wi.data();
    const double* view = wo.data();
    double* density = out.data();
    const cb_evaluator* evaluator = evaluator_;
    for_each_chunk("pdf", n, threads,
                   [&](std::size_t, std::size_t begin, std::size_t end, ChunkFailure& failure) {
                     for (std::size_t i = begin; i < end; ++i) {
                       const cb_footprint fp = footprint_at(f, i);
                       const cb_result r = cb_direction_pdf(
                           evaluator, &fp, in + 3 * i, view + 3 * i, density + i, &failure.error);
                       if (r != CB_OK) {
                         failure.index = i;
                         failure.result = r;
                         return;
                       }
                     }
                   });
  }

 private:
  cb_evaluator* evaluator_ = nullptr;
};

// Raises clothbake._errors.error_for(result, name, message) for a Failure.
void translate_failure(const std::exception_ptr& pointer, void*) {
  try {
    std::rethrow_exception(pointer);
  } catch (const Failure& failure) {
    nb::object error = nb::module_::import_("clothbake._errors")
                           .attr("error_for")(int(failure.result), cb_result_name(failure.result),
                                              failure.message);
    PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
  }
}

}  // namespace

NB_MODULE(_shading, m) {
  m.doc() = "clothbake's C interface (capi/clothbake.h); use the clothbake package instead";
  nb::register_exception_translator(translate_failure);
  m.attr("CHUNK_SIZE") = kChunkSize;
  m.attr("C_API_VERSION") = CLOTHBAKE_C_API_VERSION;
  m.def("chunk_seed", &chunk_seed, "seed"_a, "chunk"_a);
  m.def(
      "result_name", [](int result) { return std::string(cb_result_name(cb_result(result))); },
      "result"_a);

  nb::class_<Asset>(m, "Asset").def_prop_ro("source", &Asset::source).def("info", &asset_info);
  m.def("pixel_footprints", &pixel_footprints, "uv"_a, "duv_dx"_a, "duv_dy"_a, "scale"_a,
        "max_side"_a, "out"_a.noconvert());
  m.def("uv_differentials", &uv_differentials, "t"_a, "direction"_a, "ddx"_a, "ddy"_a, "normal"_a,
        "dpdu"_a, "dpdv"_a, "out_dx"_a.noconvert(), "out_dy"_a.noconvert());
  m.def("open_file", &open_file, "path"_a, "trusted"_a);
  m.def("open_memory", &open_memory, "data"_a, "trusted"_a);

  nb::class_<Evaluator>(m, "Evaluator")
      .def(nb::init<const Asset&, uint32_t, uint32_t, uint32_t, uint32_t, double>(), "asset"_a,
           "method"_a, "tables"_a, "sheen"_a, "spp"_a, "direct_max_side"_a, nb::keep_alive<1, 2>())
      .def("estimate", &Evaluator::estimate, "footprints"_a, "wi"_a, "wo"_a, "lobes"_a, "seed"_a,
           "threads"_a, "out"_a.noconvert())
      .def("sample", &Evaluator::sample, "footprints"_a, "wo"_a, "u"_a, "threads"_a,
           "out_wi"_a.noconvert(), "out_pdf"_a.noconvert(), "out_valid"_a.noconvert(),
           "out_delta"_a.noconvert())
      .def("pdf", &Evaluator::pdf, "footprints"_a, "wi"_a, "wo"_a, "threads"_a,
           "out"_a.noconvert());
}
