#include "common/diagnostics.hpp"

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <atomic>
#include <mutex>

namespace clothbake {
namespace {

std::mutex g_mutex;
std::vector<std::string> g_warnings;
std::atomic<bool> g_quiet{false};

spdlog::logger& logger() {
  static std::shared_ptr<spdlog::logger> instance = [] {
    auto sink = std::make_shared<spdlog::sinks::stderr_sink_mt>();
    auto log = std::make_shared<spdlog::logger>("clothbake", sink);
    log->set_pattern("clothbake: %v");
    log->set_level(spdlog::level::info);
    return log;
  }();
  return *instance;
}

}  // namespace

void warn(const std::string& message) {
  {
    std::lock_guard lock(g_mutex);
    g_warnings.push_back(message);
  }
  if (!g_quiet) logger().warn("warning: {}", message);
}

void info(const std::string& message) {
  if (!g_quiet) logger().info("{}", message);
}

void report_error(const std::string& message) {
  logger().error("error: {}", message);
}

void set_quiet(bool quiet) {
  g_quiet = quiet;
}
bool is_quiet() {
  return g_quiet;
}

std::vector<std::string> take_warnings() {
  std::lock_guard lock(g_mutex);
  return std::exchange(g_warnings, {});
}

}  // namespace clothbake
