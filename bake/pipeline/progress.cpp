#include "bake/pipeline/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace clothbake::pipeline {

bool ProgressBar::stderr_is_terminal() {
  return ::isatty(STDERR_FILENO) == 1;
}

void ProgressBar::begin_stage(int index, int count, const std::string& name) {
  // Appended piecewise: GCC 12 warns falsely (-Wrestrict) on "literal" + std::string.
  std::string label(1, '[');
  label.append(std::to_string(index + 1)).append("/").append(std::to_string(count));
  label.append("] ").append(name);
  begin(label);
}

void ProgressBar::begin(const std::string& label) {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  label_ = label;
  last_draw_ = {};
  best_ = 0.0;
  draw(0.0);
}

void ProgressBar::update(double fraction) {
  if (!enabled_) return;
  std::unique_lock lock(mutex_, std::try_to_lock);  // never make a worker thread wait
  if (!lock.owns_lock()) return;
  best_ = std::max(best_, fraction);
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100)) return;
  draw(best_);
}

void ProgressBar::draw(double fraction) {
  fraction = std::clamp(fraction, 0.0, 1.0);
  constexpr int kWidth = 30;
  const int filled = int(fraction * kWidth + 0.5);
  std::string bar(std::size_t(filled), '#');
  bar.append(std::size_t(kWidth - filled), '.');
  std::fprintf(stderr, "\r\033[2K%-32s [%s] %3d%%", label_.c_str(), bar.c_str(),
               int(fraction * 100 + 0.5));
  std::fflush(stderr);
  last_draw_ = std::chrono::steady_clock::now();
  drawn_ = true;
}

void ProgressBar::finish() {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  if (drawn_) {
    std::fprintf(stderr, "\r\033[2K");
    std::fflush(stderr);
    drawn_ = false;
  }
}

}  // namespace clothbake::pipeline
