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
// Resets the peak (writes "5" to /proc/self/clear_refs, Linux >= 4.0). False if not permitted,
// in which case peaks are process-wide.
bool reset_peak_rss();

}  // namespace clothbake::pipeline
