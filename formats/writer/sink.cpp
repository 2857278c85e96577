#include "formats/writer/sink.hpp"

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <thread>

#include "common/error.hpp"

namespace clothbake::formats {

void MemorySink::write(const void* data, std::size_t size) {
  const auto* p = static_cast<const std::byte*>(data);
  bytes_.insert(bytes_.end(), p, p + size);
}

FdSink::FdSink(int fd, std::string path_for_messages)
    : fd_(fd), path_(std::move(path_for_messages)) {
  if (const char* pause = std::getenv("CLOTHBAKE_TEST_PAUSE_AFTER_BYTES")) {
    char* end = nullptr;
    const long long n = std::strtoll(pause, &end, 10);
    if (end != pause && n >= 0) pause_after_ = n;
  }
}

void FdSink::write(const void* data, std::size_t size) {
  const auto* p = static_cast<const char*>(data);
  while (size > 0) {
    // Bounded chunks: write(2) transfers at most ~2 GiB per call on Linux anyway.
    const std::size_t chunk = size < (std::size_t(1) << 30) ? size : (std::size_t(1) << 30);
    const ssize_t n = ::write(fd_, p, chunk);
    if (n < 0) {
      if (errno == EINTR) continue;
      const int err = errno;
      throw_input_error("cannot write " + path_ + ": " + std::strerror(err) + " (after " +
                        std::to_string(written_) + " bytes)");
    }
    if (n == 0)
      throw_input_error("cannot write " + path_ + ": no progress (short write after " +
                        std::to_string(written_) + " bytes)");
    p += n;
    size -= std::size_t(n);
    written_ += uint64_t(n);
  }
  if (pause_after_ >= 0 && written_ >= uint64_t(pause_after_)) {
    pause_after_ = -1;  // once
    std::this_thread::sleep_for(std::chrono::seconds(60));
  }
}

}  // namespace clothbake::formats
