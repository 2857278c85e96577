#include "bake/pipeline/resource_usage.hpp"

#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <sstream>

namespace clothbake::pipeline {

double process_cpu_seconds() {
  timespec ts{};
  if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0) return 0.0;
  return double(ts.tv_sec) + double(ts.tv_nsec) * 1e-9;
}

double wall_seconds() {
  using clock = std::chrono::steady_clock;
  return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

uint64_t peak_rss_bytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) {
      std::istringstream in(line.substr(6));
      uint64_t kib = 0;
      if (in >> kib) return kib * 1024;
    }
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) == 0) return uint64_t(usage.ru_maxrss) * 1024;  // KiB on Linux
  return 0;
}

namespace {

// A number of bytes from the first line of a cgroup file; 0 for "max", a missing file or junk.
uint64_t cgroup_limit(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text) || text.empty() || text.find_first_not_of("0123456789") != std::string::npos)
    return 0;
  try {
    return std::stoull(text);
  } catch (...) {
    return 0;
  }
}

// The process's cgroup path for `prefix` of /proc/self/cgroup ("0::" for v2, "memory:" after the
// hierarchy number for v1), empty if none.
std::string own_cgroup(const std::string& prefix) {
  std::ifstream in("/proc/self/cgroup");
  std::string line;
  while (std::getline(in, line)) {
    if (prefix == "0::" && line.rfind("0::", 0) == 0) return line.substr(3);
    const auto colon = line.find(':');
    if (prefix != "0::" && colon != std::string::npos &&
        line.compare(colon + 1, prefix.size(), prefix) == 0)
      return line.substr(colon + 1 + prefix.size());
  }
  return "";
}

}  // namespace

uint64_t machine_memory_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  uint64_t total = pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : uint64_t(8) << 30;
  // The own cgroup's file when it is visible (no cgroup namespace), else the mount's root (which
  // is the own cgroup inside a container).
  uint64_t limit = 0;
  const std::string v2 = own_cgroup("0::"), v1 = own_cgroup("memory:");
  if (!v2.empty() && v2 != "/") limit = cgroup_limit("/sys/fs/cgroup" + v2 + "/memory.max");
  if (limit == 0) limit = cgroup_limit("/sys/fs/cgroup/memory.max");
  if (limit == 0 && !v1.empty() && v1 != "/")
    limit = cgroup_limit("/sys/fs/cgroup/memory" + v1 + "/memory.limit_in_bytes");
  if (limit == 0) limit = cgroup_limit("/sys/fs/cgroup/memory/memory.limit_in_bytes");
  // cgroup v1 reports "no limit" as a huge number (2^63 rounded to pages): min() ignores it.
  if (limit > 0) total = std::min(total, limit);
  // An address-space or data limit (ulimit -v / -d) ends a larger bake with an allocation failure.
  for (const int resource : {RLIMIT_AS, RLIMIT_DATA}) {
    struct rlimit rl {};
    if (::getrlimit(resource, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
      total = std::min(total, uint64_t(rl.rlim_cur));
  }
  return total;
}

bool reset_peak_rss() {
  std::ofstream clear("/proc/self/clear_refs");
  if (!clear) return false;
  clear << "5";
  clear.flush();
  return bool(clear);
}

}  // namespace clothbake::pipeline
