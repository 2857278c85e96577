// Full validation of the baked tables (formats/validate/validate.cpp): a small asset baked through
// every stage validates clean; copies whose sections are each corrupted in a way that keeps them
// structurally valid (the asset is re-serialised, so every checksum matches) fail with the stable
// check ID of docs/format.md: resolutions that disagree (CBK-E016), cross-section inconsistencies
// (CBK-E022), values out of range (CBK-E021), a missing label map (CBK-E019).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "bake/inputs/fabric_load.hpp"
#include "bake/pipeline/bake.hpp"
#include "bake/stages/stages.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/compressed_layout.hpp"
#include "formats/reader/parallax_sections.hpp"
#include "formats/reader/radiance_layout.hpp"
#include "formats/validate/validate.hpp"
#include "formats/writer/asset_writer.hpp"

using namespace clothbake;
namespace fs = std::filesystem;
using reader::SectionType;

namespace {

std::vector<std::byte> read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> bytes(chars.size());
  std::memcpy(bytes.data(), chars.data(), chars.size());
  return bytes;
}

// Every section of an asset as writer sections (payload copies), to edit and re-serialise.
std::vector<formats::Section> sections_of(const std::vector<std::byte>& bytes) {
  reader::Asset asset;
  EXPECT_TRUE(asset.open_memory(bytes.data(), bytes.size()).ok());
  std::vector<formats::Section> out;
  for (uint32_t i = 0; i < asset.section_count(); ++i) {
    reader::SectionInfo s;
    EXPECT_TRUE(asset.section(i, &s).ok());
    formats::Section w;
    w.type = s.type;
    w.instance = s.instance;
    w.version = s.version;
    w.element = s.element_type;
    w.dims.assign(s.dims, s.dims + s.rank);
    w.payload.resize(s.stored_size);
    if (s.stored_size) std::memcpy(w.payload.data(), s.data, s.stored_size);
    out.push_back(std::move(w));
  }
  return out;
}

formats::Section* find(std::vector<formats::Section>& sections, SectionType type,
                       uint32_t instance) {
  for (auto& s : sections)
    if (s.type == type && s.instance == instance) return &s;
  return nullptr;
}

struct Findings {
  std::vector<std::string> ids, messages;
  bool has(const std::string& id) const {
    for (const auto& i : ids)
      if (i == id) return true;
    return false;
  }
  std::string all() const {
    std::string text;
    for (std::size_t i = 0; i < ids.size(); ++i)
      text += ids[i] + ": " + messages[i] + "\n";
    return text;
  }
};

Findings validate(const std::vector<formats::Section>& sections) {
  const std::vector<std::byte> bytes = formats::serialize_asset(sections);
  reader::Asset asset;
  Findings f;
  const reader::Status s = asset.open_memory(bytes.data(), bytes.size());
  if (!s.ok()) {
    f.ids.push_back(reader::check_id(s.check()));
    f.messages.push_back(s.message());
    return f;
  }
  reader::validate_asset(
      asset,
      [](void* user, reader::Check check, uint32_t, const char* message) {
        auto* f = static_cast<Findings*>(user);
        f->ids.push_back(reader::check_id(check));
        f->messages.push_back(message);
      },
      &f);
  return f;
}

class ValidateTables : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const fs::path dir =
        fs::temp_directory_path() / ("clothbake_validate_tables_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    Fabric fabric = fabric_from_named_weave("twill2/1", 16).fabric;
    fabric.bake.parallax_dirs = 4;
    fabric.bake.visibility_dirs = 8;
    fabric.bake.radiance_dirs = 4;
    fabric.bake.clusters = 3;
    pipeline::BakeRequest request;
    request.fabric = fabric;
    request.output_path = (dir / "packed.cbk").string();
    request.stages = {};  // everything: compressed tables, raw ones dropped
    pipeline::bake(request, stages::bake_stages());
    packed_ = new std::vector<formats::Section>(sections_of(read_bytes(request.output_path)));
    request.output_path = (dir / "raw.cbk").string();
    request.stages = {"tables", "parallax"};
    request.fabric->bake.compress = false;  // the raw parallax codes and SATs too
    pipeline::bake(request, stages::bake_stages());
    raw_ = new std::vector<formats::Section>(sections_of(read_bytes(request.output_path)));
    fs::remove_all(dir);
  }
  static void TearDownTestSuite() {
    delete packed_;
    delete raw_;
  }
  static std::vector<formats::Section>* packed_;
  static std::vector<formats::Section>* raw_;
};
std::vector<formats::Section>* ValidateTables::packed_ = nullptr;
std::vector<formats::Section>* ValidateTables::raw_ = nullptr;

TEST_F(ValidateTables, BakedAssetsAreValid) {
  for (const auto* sections : {packed_, raw_}) {
    const Findings f = validate(*sections);
    EXPECT_TRUE(f.ids.empty()) << f.all();
  }
  // The fixtures hold what the corruptions below need.
  EXPECT_NE(find(*packed_, SectionType::RadianceCompressedTables, 2), nullptr);
  EXPECT_NE(find(*packed_, SectionType::ParallaxEntropy, 3), nullptr);  // the 1.2 default
  EXPECT_NE(find(*raw_, SectionType::ParallaxSat, 0), nullptr);
  EXPECT_NE(find(*packed_, SectionType::VisibilityAsg, 0), nullptr);
  EXPECT_NE(find(*raw_, SectionType::RadianceRawTables, 3), nullptr);
  EXPECT_NE(find(*raw_, SectionType::ClusterLabels, 0), nullptr);
}

// A label map whose labels are permuted (1 <-> 2): each section is valid on its own, but the
// tables put values in texels of other clusters.
void swap_labels(std::vector<formats::Section>& sections) {
  formats::Section* labels = find(sections, SectionType::ClusterLabels, 0);
  ASSERT_NE(labels, nullptr);
  for (auto& b : labels->payload) {
    const auto v = uint8_t(b);
    if (v == 1 || v == 2) b = std::byte(uint8_t(3 - v));
  }
}

TEST_F(ValidateTables, LabelsThatDisagreeWithTheTablesAreCrossSectionErrors) {
  auto raw = *raw_;
  swap_labels(raw);
  Findings f = validate(raw);
  EXPECT_TRUE(f.has("CBK-E022")) << f.all();
  auto packed = *packed_;
  swap_labels(packed);
  f = validate(packed);
  EXPECT_TRUE(f.has("CBK-E022")) << f.all();
}

TEST_F(ValidateTables, ParallaxSatThatIsNotTheSatOfTheCodes) {
  auto s = *raw_;
  formats::Section* sat = find(s, SectionType::ParallaxSat, 0);
  ASSERT_NE(sat, nullptr);
  uint32_t v;
  std::memcpy(&v, sat->payload.data() + 4 * 37, 4);
  v += 1;
  std::memcpy(sat->payload.data() + 4 * 37, &v, 4);
  const Findings f = validate(s);
  EXPECT_TRUE(f.has("CBK-E022")) << f.all();
  EXPECT_NE(f.all().find("parallax_sat"), std::string::npos) << f.all();
}

TEST_F(ValidateTables, ResolutionsThatDisagreeAreE016) {
  // The parallax info record claims another resolution along with a matching shape: drop the
  // parallax sections and put a consistent 8^2 parallax table in their place.
  auto s = *raw_;
  formats::Section* info = find(s, SectionType::ParallaxTable, 0);
  formats::Section* codes = find(s, SectionType::ParallaxTable, 1);
  ASSERT_NE(info, nullptr);
  ASSERT_NE(codes, nullptr);
  reader::ParallaxInfoRecord record;
  std::memcpy(&record, info->payload.data(), sizeof record);
  const uint32_t dirs = record.dirs * record.dirs;
  record.resolution = 8;
  std::memcpy(info->payload.data(), &record, sizeof record);
  codes->dims = {dirs, 8, 8};
  codes->payload.assign(std::size_t(dirs) * 64 * 2, std::byte{0});
  s.erase(
      std::remove_if(s.begin(), s.end(),
                     [](const formats::Section& x) { return x.type == SectionType::ParallaxSat; }),
      s.end());
  const Findings f = validate(s);
  EXPECT_TRUE(f.has("CBK-E016")) << f.all();
  EXPECT_NE(f.all().find("parallax"), std::string::npos) << f.all();
}

TEST_F(ValidateTables, TablesWithAnotherClusterCountAreCrossSectionErrors) {
  // The compressed info record says one cluster more than the label map has.
  auto s = *packed_;
  formats::Section* info = find(s, SectionType::RadianceCompressedTables, 0);
  ASSERT_NE(info, nullptr);
  reader::CompressedTableInfoRecord record;
  std::memcpy(&record, info->payload.data(), sizeof record);
  ASSERT_GT(record.cluster_count, 1u);
  record.cluster_count += 1;
  std::memcpy(info->payload.data(), &record, sizeof record);
  Findings f = validate(s);
  EXPECT_TRUE(f.has("CBK-E022")) << f.all();
  EXPECT_NE(f.all().find("clusters"), std::string::npos) << f.all();
  // The same on raw tables.
  auto r = *raw_;
  formats::Section* raw_info = find(r, SectionType::RadianceRawTables, 0);
  ASSERT_NE(raw_info, nullptr);
  reader::RadianceTableInfoRecord raw_record;
  std::memcpy(&raw_record, raw_info->payload.data(), sizeof raw_record);
  raw_record.cluster_count += 1;
  std::memcpy(raw_info->payload.data(), &raw_record, sizeof raw_record);
  f = validate(r);
  EXPECT_TRUE(f.has("CBK-E022")) << f.all();
}

TEST_F(ValidateTables, ViewOpenFailuresKeepTheirIds) {
  // A compressed cell map naming a cell that does not exist: the reader's open() says CBK-E021.
  auto s = *packed_;
  formats::Section* map = find(s, SectionType::RadianceCompressedTables, 2);
  ASSERT_NE(map, nullptr);
  map->payload[5] = std::byte{200};
  Findings f = validate(s);
  EXPECT_TRUE(f.has("CBK-E021")) << f.all();
  // A raw SAT that decreases (a negative texel value): CBK-E021 from check_contents.
  auto r = *raw_;
  formats::Section* sat = find(r, SectionType::RadianceRawTables, 3);
  ASSERT_NE(sat, nullptr);
  const std::size_t element = sat->element == reader::ElementType::U32 ? 4 : 8;
  std::memset(sat->payload.data() + sat->payload.size() - element, 0, element);
  f = validate(r);
  EXPECT_TRUE(f.has("CBK-E021")) << f.all();
  // Tables without a label map: CBK-E019.
  auto m = *raw_;
  m.erase(std::remove_if(m.begin(), m.end(),
                         [](const formats::Section& x) {
                           return x.type == SectionType::ClusterLabels ||
                                  x.type == SectionType::ClusterMeanVisibility;
                         }),
          m.end());
  f = validate(m);
  EXPECT_TRUE(f.has("CBK-E019")) << f.all();
  // A visibility ASG record section of the wrong shape: CBK-E015 from VisibilityAsgView::open.
  auto v = *packed_;
  formats::Section* asg = find(v, SectionType::VisibilityAsg, 1);
  ASSERT_NE(asg, nullptr);
  asg->dims[0] = asg->dims[0] / 2;
  asg->payload.resize(asg->payload.size() / 2);
  f = validate(v);
  EXPECT_TRUE(f.has("CBK-E015")) << f.all();
}

}  // namespace
