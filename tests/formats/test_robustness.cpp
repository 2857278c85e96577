// The reader on damaged bytes: truncation at every prefix length, every single-byte corruption of
// the header and the table, corruption of payload bytes, and random garbage. Each must give a
// clean error (the right class and check ID), never a crash or an out-of-bounds read. This file
// uses only the reader library, so that it is also built with AddressSanitizer and
// UndefinedBehaviorSanitizer (formats_reader_asan_test).
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <vector>

#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/validate/checksums.hpp"
#include "formats/validate/validate.hpp"

namespace {

using namespace clothbake::reader;

const char* kGolden = CLOTHBAKE_SOURCE_DIR "/tests/formats/data/golden_v2.cbk";

// Exact-size copy of a byte string (AddressSanitizer then sees any read past its end); operator
// new[] returns memory aligned for any fundamental type, as the reader requires.
class Buffer {
 public:
  explicit Buffer(const std::vector<unsigned char>& bytes)
      : bytes_(new unsigned char[bytes.empty() ? 1 : bytes.size()]), size_(bytes.size()) {
    if (!bytes.empty()) std::memcpy(bytes_.get(), bytes.data(), bytes.size());
  }
  const void* data() const { return bytes_.get(); }
  std::size_t size() const { return size_; }

 private:
  std::unique_ptr<unsigned char[]> bytes_;
  std::size_t size_;
};

std::vector<unsigned char> golden_bytes() {
  std::ifstream in(kGolden, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Everything a consumer might do with an asset that opened.
void exercise(const Asset& asset) {
  FeatureMaps maps;
  if (read_feature_maps(asset, &maps).ok()) {
    volatile float sink = 0;
    for (float v : maps.height)
      sink = sink + v;
    for (float v : maps.albedo)
      sink = sink + v;
    for (uint16_t v : maps.yarn_id)
      sink = sink + float(v);
  }
  const FabricInfoRecord* info;
  (void)read_fabric_info(asset, &info);
  ArrayView<YarnMaterialRecord> yarns;
  if (read_yarn_materials(asset, &yarns).ok())
    for (const auto& y : yarns)
      (void)std::strlen(y.name);
  std::string_view json;
  (void)asset.metadata_json(&json);
  validate_asset(asset, nullptr, nullptr);
}

TEST(Robustness, GoldenFileOpens) {
  const auto bytes = golden_bytes();
  ASSERT_GT(bytes.size(), 64u);
  Buffer buffer(bytes);
  Asset asset;
  Status status = asset.open_memory(buffer.data(), buffer.size());
  ASSERT_TRUE(status.ok()) << status.message();
  exercise(asset);
}

TEST(Robustness, EveryTruncationIsAClean_Truncated_Error) {
  const auto bytes = golden_bytes();
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    std::vector<unsigned char> prefix(bytes.begin(), bytes.begin() + std::ptrdiff_t(n));
    Buffer buffer(prefix);
    Asset asset;
    const Status status = asset.open_memory(buffer.data(), buffer.size());
    ASSERT_FALSE(status.ok()) << "prefix " << n;
    ASSERT_EQ(status.code(), ErrorCode::Truncated) << "prefix " << n << ": " << status.message();
    ASSERT_STREQ(status.check_id(), "CBK-E002");
    ASSERT_FALSE(asset.is_open());
  }
}

TEST(Robustness, EverySingleByteCorruptionOfHeaderAndTableIsRejectedByOpenOrTheChecksum) {
  // open() refuses what breaks the structure; what it accepts (a flip in a field it does not
  // interpret, or one that leaves the structure valid) the header checksum catches.
  const auto bytes = golden_bytes();
  uint32_t count;
  std::memcpy(&count, bytes.data() + 12, 4);
  const std::size_t table_end = 64 + std::size_t(count) * 64;
  int opened = 0;
  for (std::size_t offset = 0; offset < table_end; ++offset)
    for (unsigned flip : {0x01u, 0x80u, 0xffu}) {
      auto damaged = bytes;
      damaged[offset] ^= static_cast<unsigned char>(flip);
      Buffer buffer(damaged);
      Asset asset;
      Status status = asset.open_memory(buffer.data(), buffer.size());
      if (status.ok()) {
        ++opened;
        exercise(asset);
        status = verify_checksums(asset);
        ASSERT_EQ(status.check(), Check::HeaderChecksum) << "offset " << offset << " xor " << flip;
        ASSERT_EQ(status.code(), ErrorCode::Corrupt);
        continue;
      }
      ASSERT_NE(status.check(), Check::None) << status.message();
      if (offset < 8) {
        ASSERT_EQ(status.code(), ErrorCode::NotAnAsset) << status.message();
      } else if (offset < 10) {
        ASSERT_EQ(status.code(), ErrorCode::UnsupportedVersion) << status.message();
      }
    }
  // The flags, reserved bytes, checksum and table checksums are not structure: some flips open.
  EXPECT_GT(opened, 0);
}

TEST(Robustness, PayloadCorruptionIsACorruptSection) {
  const auto bytes = golden_bytes();
  uint32_t count;
  std::memcpy(&count, bytes.data() + 12, 4);
  const std::size_t payload_start = 64 + std::size_t(count) * 64;
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    auto damaged = bytes;
    const std::size_t offset = payload_start + rng() % (bytes.size() - payload_start);
    damaged[offset] ^= 0x10;
    Buffer buffer(damaged);
    Asset asset;
    // open() reads no payload byte: the asset opens, is usable, and the checksums name the
    // section (or, for a padding byte, only validation sees it).
    Status status = asset.open_memory(buffer.data(), buffer.size());
    ASSERT_TRUE(status.ok()) << status.message();
    exercise(asset);
    const auto summary = validate_asset(asset, nullptr, nullptr);
    ASSERT_GT(summary.errors, 0u) << "offset " << offset;
    bool in_a_payload = false;
    for (uint32_t i = 0; i < asset.section_count(); ++i) {
      SectionInfo info;
      ASSERT_TRUE(asset.section(i, &info).ok());
      in_a_payload |= offset >= info.offset && offset - info.offset < info.stored_size;
    }
    status = verify_checksums(asset);
    if (!in_a_payload) {  // padding: no checksum covers it
      ASSERT_TRUE(status.ok()) << status.message();
      continue;
    }
    ASSERT_EQ(status.code(), ErrorCode::Corrupt) << "offset " << offset;
    ASSERT_STREQ(status.check_id(), "CBK-E012");
  }
}

TEST(Robustness, RandomMutationsAreOpenedOrRefusedNeverCrash) {
  // open() does not verify the header checksum, so every mutation reaches the structural checks.
  const auto bytes = golden_bytes();
  uint32_t count;
  std::memcpy(&count, bytes.data() + 12, 4);
  const std::size_t table_end = 64 + std::size_t(count) * 64;
  std::mt19937 rng(11);
  int opened = 0, refused = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    auto damaged = bytes;
    const int flips = 1 + int(rng() % 4);
    for (int k = 0; k < flips; ++k)
      damaged[8 + rng() % (table_end - 8)] = uint8_t(rng());
    damaged[8] = 2, damaged[9] = 0;  // keep major 2
    Buffer buffer(damaged);
    Asset asset;
    const Status status = asset.open_memory(buffer.data(), buffer.size());
    if (status.ok()) {
      ++opened;
      exercise(asset);
    } else {
      ++refused;
      // A refusal is a named structural error, never a bare failure.
      EXPECT_NE(status.check(), Check::None) << status.message();
      EXPECT_NE(status.code(), ErrorCode::InvalidArgument) << status.message();
    }
  }
  // The mutations reach both sides of the checks: some damaged tables still describe a valid
  // layout (a changed instance or checksum field of a section the structure check does not
  // verify), most do not. Either side staying empty would mean the test no longer exercises it.
  EXPECT_GT(opened, 0) << refused << " refused";
  EXPECT_GT(refused, 0) << opened << " opened";
  std::printf("random mutations: %d opened, %d refused\n", opened, refused);
}

TEST(Robustness, ArgumentsAreChecked) {
  Asset asset;
  EXPECT_EQ(asset.open_memory(nullptr, 10).code(), ErrorCode::InvalidArgument);
  const auto bytes = golden_bytes();
  std::vector<unsigned char> shifted(bytes.size() + 8);
  unsigned char* misaligned = shifted.data() + 1;
  while (reinterpret_cast<uintptr_t>(misaligned) % 8 == 0)
    ++misaligned;
  std::memcpy(misaligned, bytes.data(), bytes.size());
  EXPECT_EQ(asset.open_memory(misaligned, bytes.size()).code(), ErrorCode::InvalidArgument);
  SectionInfo info;
  EXPECT_EQ(asset.section(0, &info).code(), ErrorCode::InvalidArgument);  // not open
  Buffer buffer(bytes);
  ASSERT_TRUE(asset.open_memory(buffer.data(), buffer.size()).ok());
  EXPECT_EQ(asset.section(asset.section_count(), &info).code(), ErrorCode::InvalidArgument);
  info.index = 1000;
  ArrayView<float> view;
  EXPECT_FALSE(asset.view_of(info, &view).ok());
}

}  // namespace
