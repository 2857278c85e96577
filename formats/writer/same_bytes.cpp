#include "formats/writer/same_bytes.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "formats/writer/sink.hpp"

namespace clothbake::formats {
namespace {

struct Differs {};  // thrown by the sink at the first difference (stops the writer early)

// Compares what the writer appends with the next bytes of an open file.
class CompareSink final : public Sink {
 public:
  explicit CompareSink(int fd) : fd_(fd) {}
  void write(const void* data, std::size_t size) override {
    const auto* p = static_cast<const std::byte*>(data);
    while (size > 0) {
      const std::size_t n = std::min(size, buffer_.size());
      std::size_t got = 0;
      while (got < n) {
        const ssize_t r = ::read(fd_, buffer_.data() + got, n - got);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) throw Differs{};
        got += std::size_t(r);
      }
      if (std::memcmp(buffer_.data(), p, n) != 0) throw Differs{};
      p += n;
      size -= n;
    }
  }

 private:
  int fd_;
  std::vector<std::byte> buffer_ = std::vector<std::byte>(1 << 20);
};

}  // namespace

bool file_holds_asset(const std::filesystem::path& path, SectionRefs sections) {
  check_sections(sections);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  struct stat st {};
  bool same =
      ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && uint64_t(st.st_size) == asset_size(sections);
  if (same) {
    CompareSink sink(fd);
    try {
      write_asset(sections, sink);
    } catch (const Differs&) {
      same = false;
    }
  }
  ::close(fd);
  return same;
}

}  // namespace clothbake::formats
