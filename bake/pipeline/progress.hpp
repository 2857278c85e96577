// A one-line progress bar on stderr: "[2/4] feature_maps [#######.....]  58%". Redrawn at most
// ten times a second with a carriage return; cleared when done. Disabled objects print nothing.
// The bar never steps back within one label: updates that arrive out of order (worker threads
// report their own fractions) keep the largest fraction seen since begin().
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>

namespace clothbake::pipeline {

class ProgressBar {
 public:
  explicit ProgressBar(bool enabled) : enabled_(enabled) {}
  ~ProgressBar() { finish(); }

  // True when stderr is a terminal (the default for the bar: off in logs and pipes).
  static bool stderr_is_terminal();
  // Whether the bar draws (what it was made with): a command's other terminal-only lines follow it.
  bool enabled() const noexcept { return enabled_; }

  void begin_stage(int index, int count, const std::string& name);
  // Any label ("[3/28] multiscale 8 spp"); the fraction restarts at 0.
  void begin(const std::string& label);
  // Thread-safe; cheap when called often.
  void update(double fraction);
  void finish();

 private:
  void draw(double fraction);

  bool enabled_;
  std::mutex mutex_;
  std::string label_;
  std::chrono::steady_clock::time_point last_draw_{};
  double best_ = 0.0;  // the largest fraction since begin()
  bool drawn_ = false;
};

}  // namespace clothbake::pipeline
