// Opens every asset named on the command line with the reader library, verifies its checksums
// (the opt-in clothbake::reader_validate; a renderer that trusts its storage may skip this) and
// prints its section count; exit 1 if one does not open or is corrupt.
#include <cstdio>

#include "formats/reader/asset.hpp"
#include "formats/validate/checksums.hpp"

int main(int argc, char** argv) {
  int status = 0;
  for (int i = 1; i < argc; ++i) {
    clothbake::reader::Asset asset;
    clothbake::reader::Status s = asset.open_file(argv[i]);
    if (s.ok()) s = clothbake::reader::verify_checksums(asset);
    if (!s.ok()) {
      std::fprintf(stderr, "%s: %s\n", argv[i], s.message());
      status = 1;
      continue;
    }
    std::printf("%s: %u sections\n", argv[i], unsigned(asset.section_count()));
  }
  return status;
}
