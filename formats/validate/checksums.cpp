// Checksum verification (checksums.hpp).
#include "formats/validate/checksums.hpp"

#include <cinttypes>

#include "formats/validate/xxh64.hpp"

namespace clothbake::reader {

Status verify_header_checksum(const Asset& asset) noexcept {
  if (!asset.is_open())
    return Status::error(ErrorCode::InvalidArgument, Check::None, "asset not open");
  const FileHeader& header = asset.header();
  Xxh64Stream hash(0);
  hash.update(asset.bytes(), kHeaderChecksumOffset);
  hash.update(asset.bytes() + sizeof(FileHeader),
              std::size_t(uint64_t(header.section_count) * header.section_entry_size));
  const uint64_t computed = hash.digest();
  if (computed != header.header_checksum)
    return Status::error(ErrorCode::Corrupt, Check::HeaderChecksum,
                         "header checksum mismatch (stored %016" PRIx64 ", computed %016" PRIx64
                         "): the header or section table is corrupt",
                         header.header_checksum, computed);
  return {};
}

Status verify_section(const Asset& asset, const SectionInfo& section) noexcept {
  SectionInfo fresh;
  Status status = asset.section(section.index, &fresh);
  if (!status.ok()) return status;
  const uint64_t sum = xxh64(fresh.data, std::size_t(fresh.stored_size), 0);
  if (sum == fresh.checksum) return {};
  char what[96];
  return Status::error(
      ErrorCode::Corrupt, Check::SectionChecksum,
      "%s: checksum mismatch (stored %016" PRIx64 ", computed %016" PRIx64
      "): its payload is corrupt",
      describe_section(what, sizeof what, fresh.index, uint32_t(fresh.type), fresh.instance),
      fresh.checksum, sum);
}

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
Status verify_checksums(const Asset& asset) noexcept {
  Status status = verify_header_checksum(asset);
  for (uint32_t i = 0; status.ok() && i < asset.section_count(); ++i) {
    SectionInfo info;
    info.index = i;
    status = verify_section(asset, info);
  }
  return status;
}
#endif

}  // namespace clothbake::reader
