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
std::atomic<std::string (*)(std::string_view)> g_filter{nullptr};

std::string shown(const std::string& message) {
  const auto filter = g_filter.load();
  return filter ? filter(message) : message;
}

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
  if (!g_quiet) logger().warn("warning: {}", shown(message));
}

void info(const std::string& message) {
  if (!g_quiet) logger().info("{}", shown(message));
}

void report_error(const std::string& message) {
  logger().error("error: {}", shown(message));
}

void set_message_filter(std::string (*filter)(std::string_view)) {
  g_filter = filter;
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
