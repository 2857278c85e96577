// Byte sinks for the writer: where an asset's bytes go. The file sink reports short writes and
// errors (disk full, file size limit) as clothbake::Error(Input) naming the file; tests wrap it in
// a fault-injecting sink to simulate a disk that fills up mid-write.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace clothbake::formats {

class Sink {
 public:
  virtual ~Sink() = default;
  // Appends `size` bytes or throws clothbake::Error; never writes part silently.
  virtual void write(const void* data, std::size_t size) = 0;
};

// Appends to a vector.
class MemorySink final : public Sink {
 public:
  void write(const void* data, std::size_t size) override;
  std::vector<std::byte>& bytes() { return bytes_; }

 private:
  std::vector<std::byte> bytes_;
};

// Writes to an open file descriptor (not owned). Retries on EINTR and short writes; any other
// failure, including a write that makes no progress, throws Error(Input) "cannot write PATH: ...".
//
// Test hook: if the environment variable CLOTHBAKE_TEST_PAUSE_AFTER_BYTES=N is set, the sink
// sleeps (up to 60 s) once N bytes have been written, so that a test can SIGKILL a bake mid-write.
class FdSink final : public Sink {
 public:
  FdSink(int fd, std::string path_for_messages);
  void write(const void* data, std::size_t size) override;
  uint64_t written() const { return written_; }

 private:
  int fd_;
  std::string path_;
  uint64_t written_ = 0;
  int64_t pause_after_ = -1;
};

}  // namespace clothbake::formats
