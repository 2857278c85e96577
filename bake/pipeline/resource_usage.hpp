// Process measurements for the bake report: wall time, CPU time and peak resident memory.
#pragma once

#include <cstdint>
#include <string>

namespace clothbake::pipeline {

// CPU time of the whole process (all threads), seconds: CLOCK_PROCESS_CPUTIME_ID.
double process_cpu_seconds();
// Monotonic wall clock, seconds.
double wall_seconds();
// Peak resident set size so far, bytes: VmHWM of /proc/self/status, else getrusage ru_maxrss.
uint64_t peak_rss_bytes();
// Memory this process can have: physical RAM (sysconf _SC_PHYS_PAGES x _SC_PAGE_SIZE), or the
// cgroup's limit (cgroup v2 memory.max of the process's own cgroup, else v1
// memory.limit_in_bytes) or the process's address-space or data limit (RLIMIT_AS, RLIMIT_DATA:
// ulimit -v, -d) when smaller. The default of `bake --max-memory` (all of it) and of `batch
// --max-memory` (80 %). 8 GiB when nothing can be read.
uint64_t machine_memory_bytes();

// Resets the peak (writes "5" to /proc/self/clear_refs, Linux >= 4.0). False if not permitted,
// in which case peaks are process-wide.
bool reset_peak_rss();

}  // namespace clothbake::pipeline
