// clothbake._bake: a fabric baked into an asset through the bake library, the entry `clothbake
// bake` calls (pipeline::bake over stages::bake_stages()), with progress reported to a Python
// callable. The public API and its contract are clothbake.bake's (python/clothbake/__init__.py,
// docs/python.md).
//
// Threads: the bake runs on a thread of its own with the GIL released; the calling thread waits
// for its progress reports and calls the Python callable with them, taking the GIL only for that
// (and for a signal check every 100 ms, so that Ctrl-C cancels a bake). A callable that raises (or
// a KeyboardInterrupt) cancels the bake at its next progress report: the report throws Cancelled,
// which the stage, TBB and the driver carry out of pipeline::bake. The asset is written to a
// temporary file and renamed into place only after a bake that was not cancelled, so that an
// exception from the callable leaves no asset (and the previous file untouched).
#include <nanobind/nanobind.h>
#include <nanobind/stl/string.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bake/pipeline/bake.hpp"
#include "bake/pipeline/resource_usage.hpp"
#include "bake/stages/memory_estimate.hpp"
#include "bake/stages/stages.hpp"
#include "common/diagnostics.hpp"
#include "common/error.hpp"
#include "compress/compress_settings.hpp"
#include "formats/writer/atomic_file.hpp"

namespace nb = nanobind;
using namespace nb::literals;

namespace clothbake::python_bake {
namespace {

// Thrown by a progress report after the Python side asked for cancellation.
struct Cancelled : std::exception {
  const char* what() const noexcept override { return "bake cancelled by its progress callback"; }
};

// A failed bake (clothbake::Error): raised as clothbake.BakeError with the exit code's name.
struct BakeFailure {
  std::string code;
  std::string message;
};

const char* exit_code_name(ExitCode code) {
  switch (code) {
    case ExitCode::Ok:
      return "ok";
    case ExitCode::Usage:
      return "usage";
    case ExitCode::Input:
      return "input";
    case ExitCode::InvalidAsset:
      return "invalid_asset";
    case ExitCode::Internal:
      return "internal";
    case ExitCode::VerificationFailed:
      return "verification_failed";
  }
  return "internal";
}

// Progress reports from the bake's threads to the calling thread. Within a stage only increasing
// fractions pass, in steps of at least 1 % (plus the stage's 0 and 1); a report the caller has not
// taken yet is replaced by a later one of the same stage, so the callable never lags behind.
class ProgressQueue {
 public:
  // Any bake thread. Throws Cancelled once cancel() was called.
  void report(const std::string& stage, double fraction) {
    if (cancelled_.load(std::memory_order_relaxed)) throw Cancelled();
    std::lock_guard<std::mutex> lock(mutex_);
    if (stage != stage_) {
      stage_ = stage;
      best_ = -1.0;
      sent_ = -1.0;
    }
    if (!(fraction > best_)) return;
    best_ = fraction;
    if (fraction > 0.0 && fraction < 1.0 && fraction - sent_ < 0.01) return;
    sent_ = fraction;
    if (!events_.empty() && events_.back().first == stage && events_.back().second > 0.0 &&
        events_.back().second < 1.0)
      events_.back().second = fraction;
    else
      events_.emplace_back(stage, fraction);
    wake_.notify_one();
  }

  // The bake thread, once, whatever the outcome.
  void finish() {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = true;
    wake_.notify_one();
  }

  // The calling thread, GIL released: waits up to `timeout` for reports, moves them into `out`;
  // true when the bake has finished and every report was taken.
  bool take(std::vector<std::pair<std::string, double>>& out, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    wake_.wait_for(lock, timeout, [this] { return done_ || !events_.empty(); });
    out.swap(events_);
    events_.clear();
    return done_ && out.empty();
  }

  void cancel() { cancelled_.store(true, std::memory_order_relaxed); }

 private:
  std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<std::pair<std::string, double>> events_;
  std::string stage_;
  double best_ = -1.0, sent_ = -1.0;
  bool done_ = false;
  std::atomic<bool> cancelled_{false};
};

// Bakes the fabric description at `fabric` into the asset `output` (clothbake.bake's contract).
// `progress`: None or a callable(stage: str, fraction: float). `resolution` 0: the fabric's own;
// `threads` 0: every core; `max_memory` 0: the machine's memory. Returns the summary as a dict.
nb::dict bake(const std::string& fabric, const std::string& output, nb::object progress,
              int resolution, int threads, bool force, uint64_t max_memory) {
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw nb::type_error("progress must be a callable(stage: str, fraction: float) or None");
  if (threads < 0) throw nb::value_error("threads must be >= 0 (0: every core)");
  if (resolution < 0) throw nb::value_error("resolution must be > 0 (0: the fabric's own)");

  pipeline::BakeRequest request;
  request.fabric_path = fabric;
  request.output_path = output;
  request.force = force;
  request.defer_commit = true;  // renamed into place below, unless cancelled
  request.run.threads = threads;
  if (resolution > 0) request.seeds.put(stages::kFabricResolutionArtifact, resolution);
  ProgressQueue queue;
  request.run.progress = [&queue](const std::string& stage, double fraction) {
    queue.report(stage, fraction);
  };

  std::optional<pipeline::BakeResult> result;
  std::exception_ptr failure;
  std::vector<std::string> warnings;
  std::optional<nb::python_error> raised;  // by the callable, or a signal
  std::thread worker;
  {
    nb::gil_scoped_release release;
    worker = std::thread([&]() noexcept {
      const bool was_quiet = is_quiet();
      set_quiet(true);  // the library's messages go to BakeResult.warnings, not to stderr
      try {
        take_warnings();
        const uint64_t limit = max_memory > 0 ? max_memory : pipeline::machine_memory_bytes();
        stages::check_fabric_memory(fabric, compress::CompressRequest{}, {}, threads, limit,
                                    resolution > 0 ? std::optional<int>(resolution) : std::nullopt);
        result = pipeline::bake(request, stages::bake_stages());
        warnings = take_warnings();
      } catch (...) {
        failure = std::current_exception();
      }
      set_quiet(was_quiet);
      queue.finish();
    });
  }
  std::vector<std::pair<std::string, double>> events;
  for (;;) {
    bool finished;
    {
      nb::gil_scoped_release release;
      finished = queue.take(events, std::chrono::milliseconds(100));
    }
    for (const auto& [stage, fraction] : events) {
      if (raised || progress.is_none()) break;
      try {
        progress(stage, fraction);
      } catch (nb::python_error& e) {
        raised.emplace(std::move(e));
        queue.cancel();
      }
    }
    if (!raised && PyErr_CheckSignals() != 0) {
      raised.emplace();  // fetches the KeyboardInterrupt (or whatever a handler raised)
      queue.cancel();
    }
    if (finished) break;
  }
  {
    nb::gil_scoped_release release;
    worker.join();
  }
  if (raised) throw std::move(*raised);  // the temporary asset was removed with `result`
  if (failure) {
    try {
      std::rethrow_exception(failure);
    } catch (const Error& e) {
      throw BakeFailure{exit_code_name(e.code()), e.what()};
    }
  }
  pipeline::AssetSummary& asset = result->asset;
  {
    nb::gil_scoped_release release;
    try {
      if (asset.pending) asset.pending->commit();
      if (asset.unchanged) formats::remove_stale_temp_files(asset.path);
    } catch (const Error& e) {
      throw BakeFailure{exit_code_name(e.code()), e.what()};
    }
  }

  nb::list stages;
  for (const auto& s : result->run.stages)
    stages.append(nb::make_tuple(s.name, s.wall_seconds));
  nb::list warning_list;
  for (const auto& w : warnings)
    warning_list.append(w);
  nb::dict summary;
  summary["path"] = asset.path;
  summary["size_bytes"] = asset.size_bytes;
  summary["content_hash"] = asset.content_hash;
  summary["unchanged"] = asset.unchanged;
  summary["wall_seconds"] = result->run.wall_seconds;
  summary["threads"] = result->run.threads;
  summary["stages"] = stages;
  summary["warnings"] = warning_list;
  return summary;
}

// Raises clothbake._errors.BakeError(code, message) for a BakeFailure.
void translate_failure(const std::exception_ptr& pointer, void*) {
  try {
    std::rethrow_exception(pointer);
  } catch (const BakeFailure& failure) {
    nb::object error =
        nb::module_::import_("clothbake._errors").attr("BakeError")(failure.code, failure.message);
    PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
  }
}

}  // namespace
}  // namespace clothbake::python_bake

NB_MODULE(_bake, m) {
  using namespace clothbake::python_bake;
  m.doc() = "clothbake's bake library (pipeline::bake); use clothbake.bake instead";
  nb::register_exception_translator(translate_failure);
  m.def("bake", &bake, "fabric"_a, "output"_a, "progress"_a.none(), "resolution"_a, "threads"_a,
        "force"_a, "max_memory"_a);
}
