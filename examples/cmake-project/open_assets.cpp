// Opens every asset named on the command line with the reader library and prints its section
// count; exit 1 if one does not open.
#include <cstdio>

#include "formats/reader/asset.hpp"

int main(int argc, char** argv) {
  int status = 0;
  for (int i = 1; i < argc; ++i) {
    clothbake::reader::Asset asset;
    const clothbake::reader::Status s = asset.open_file(argv[i]);
    if (!s.ok()) {
      std::fprintf(stderr, "%s: %s\n", argv[i], s.message());
      status = 1;
      continue;
    }
    std::printf("%s: %u sections\n", argv[i], unsigned(asset.section_count()));
  }
  return status;
}
