// The write stage with sections from several stages: superseded section artifacts are left out
// (and named in the metadata), sections are written from references (the pointer API of the
// writer gives the same bytes as the array API), and a bake's seeds reach the stages.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <random>

#include "bake/pipeline/bake.hpp"
#include "bake/pipeline/driver.hpp"
#include "bake/stages/stages.hpp"
#include "common/error.hpp"
#include "formats/reader/asset.hpp"
#include "formats/validate/checksums.hpp"
#include "formats/writer/asset_writer.hpp"
#include "formats/writer/sink.hpp"
#include "tests/formats/test_fabric.hpp"

namespace {

using namespace clothbake;
namespace fs = std::filesystem;
using formats::Section;
using pipeline::Stage;
using pipeline::StageContext;

Section u32_section(reader::SectionType type, uint32_t instance, uint32_t first, uint32_t count) {
  std::vector<uint32_t> values(count);
  for (uint32_t i = 0; i < count; ++i)
    values[i] = first + i;
  return formats::make_array_section<uint32_t>(type, instance, values, {count});
}

// The write and fabric_records stages plus test stages: "big" produces
// section/big (two raw-table sections), "small" section/small (one compressed-table section),
// and "replace" (optional) supersedes/replace = `superseded`.
std::vector<Stage> stages_with(bool with_replace, std::vector<std::string> superseded) {
  std::vector<Stage> list = {stages::fabric_records_stage(), stages::write_stage()};
  Stage big;
  big.name = "big";
  big.outputs = {"section/big"};
  big.run = [](StageContext& ctx) {
    std::vector<Section> v;
    v.push_back(u32_section(reader::SectionType::RadianceRawTables, 0, 100, 1000));
    v.push_back(u32_section(reader::SectionType::RadianceRawTables, 1, 7, 10));
    ctx.output("section/big", std::move(v));
  };
  list.push_back(big);
  Stage small;
  small.name = "small";
  small.outputs = {"section/small"};
  small.run = [](StageContext& ctx) {
    std::vector<Section> v;
    v.push_back(u32_section(reader::SectionType::RadianceCompressedTables, 0, 5, 4));
    ctx.output("section/small", std::move(v));
  };
  list.push_back(small);
  if (with_replace) {
    Stage replace;
    replace.name = "replace";
    replace.inputs = {"section/big"};  // like compress: it reads what it supersedes
    replace.outputs = {"supersedes/replace"};
    replace.run = [superseded](StageContext& ctx) { ctx.output("supersedes/replace", superseded); };
    list.push_back(replace);
  }
  return list;
}

class WriteStage : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("clothbake-write-stage-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs the stages and returns the written asset's section types and its metadata.
  std::vector<std::pair<uint32_t, uint32_t>> run(const std::vector<Stage>& stages,
                                                 nlohmann::json* metadata) {
    pipeline::Artifacts seeded;
    seeded.put("fabric", test_support::make_test_fabric(4));
    const std::string path = (dir_ / "a.cbk").string();
    seeded.put("output", pipeline::OutputRequest{path, false});
    pipeline::run_pipeline({}, std::move(seeded), {}, stages);
    reader::Asset asset;
    EXPECT_TRUE(asset.open_file(path.c_str()).ok() && reader::verify_checksums(asset).ok());
    std::vector<std::pair<uint32_t, uint32_t>> out;
    for (uint32_t i = 0; i < asset.section_count(); ++i) {
      reader::SectionInfo info;
      (void)asset.section(i, &info);
      out.emplace_back(uint32_t(info.type), info.instance);
    }
    std::string_view text;
    EXPECT_TRUE(asset.metadata_json(&text).ok());
    *metadata = nlohmann::json::parse(text);
    return out;
  }
  static bool has(const std::vector<std::pair<uint32_t, uint32_t>>& s, reader::SectionType t) {
    return std::any_of(s.begin(), s.end(), [t](const auto& p) { return p.first == uint32_t(t); });
  }
  fs::path dir_;
};

TEST_F(WriteStage, WritesEverySectionWithoutASupersedingStage) {
  nlohmann::json metadata;
  const auto sections = run(stages_with(false, {}), &metadata);
  EXPECT_TRUE(has(sections, reader::SectionType::RadianceRawTables));
  EXPECT_TRUE(has(sections, reader::SectionType::RadianceCompressedTables));
  EXPECT_EQ(sections.size(), 6u);  // fabric records (2), big (2), small (1), metadata (1)
  EXPECT_FALSE(metadata.contains("omitted_sections"));
}

TEST_F(WriteStage, LeavesOutSupersededSectionsAndSaysSo) {
  nlohmann::json metadata;
  const auto sections = run(stages_with(true, {"section/big"}), &metadata);
  EXPECT_FALSE(has(sections, reader::SectionType::RadianceRawTables));
  EXPECT_TRUE(has(sections, reader::SectionType::RadianceCompressedTables));
  ASSERT_TRUE(metadata.contains("omitted_sections"));
  EXPECT_EQ(metadata["omitted_sections"],
            nlohmann::json::parse(R"([{"artifact": "section/big", "superseded_by": "replace"}])"));
}

TEST_F(WriteStage, AnEmptySupersedesListChangesNothing) {
  nlohmann::json metadata;
  const auto sections = run(stages_with(true, {}), &metadata);
  EXPECT_TRUE(has(sections, reader::SectionType::RadianceRawTables));
  EXPECT_FALSE(metadata.contains("omitted_sections"));
}

TEST_F(WriteStage, SupersedingANonSectionArtifactIsAnInternalError) {
  nlohmann::json metadata;
  try {
    run(stages_with(true, {"metadata/big"}), &metadata);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Internal);
    EXPECT_NE(std::string(e.what()).find("'metadata/big', which is not a section artifact"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "a.cbk"));
}

TEST(WriterRefs, PointerApiGivesTheSameBytesInAnyOrder) {
  std::vector<Section> sections;
  for (uint32_t i = 0; i < 6; ++i)
    sections.push_back(u32_section(reader::SectionType::RadianceRawTables, 5 - i, i, 3 + i));
  sections.push_back(formats::make_metadata_section({{"k", "v"}}));
  const std::vector<std::byte> reference = formats::serialize_asset(sections);
  std::vector<const Section*> refs;
  for (const Section& s : sections)
    refs.push_back(&s);
  std::mt19937 rng(3);
  for (int round = 0; round < 4; ++round) {
    std::shuffle(refs.begin(), refs.end(), rng);
    formats::MemorySink sink;
    const uint64_t size = formats::write_asset(formats::SectionRefs(refs), sink);
    EXPECT_EQ(size, reference.size());
    EXPECT_EQ(formats::asset_size(formats::SectionRefs(refs)), reference.size());
    EXPECT_TRUE(sink.bytes() == reference) << "round " << round;
  }
}

TEST(WriterRefs, NullAndDuplicateSectionsAreInternalErrors) {
  const Section a = u32_section(reader::SectionType::RadianceRawTables, 1, 0, 4);
  const Section b = u32_section(reader::SectionType::RadianceRawTables, 1, 9, 4);
  formats::MemorySink sink;
  std::vector<const Section*> refs{&a, nullptr};
  EXPECT_THROW(formats::write_asset(formats::SectionRefs(refs), sink), Error);
  refs = {&a, &b};
  try {
    formats::write_asset(formats::SectionRefs(refs), sink);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Internal);
    EXPECT_NE(std::string(e.what()).find("two sections"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(sink.bytes().empty()) << "nothing is written before the checks";
}

TEST(BakeSeeds, SeedsAreMergedAndMayNotShadowTheBakesOwnArtifacts) {
  const fs::path dir =
      fs::temp_directory_path() / ("clothbake-bake-seeds-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  pipeline::BakeRequest request;
  request.fabric = test_support::make_test_fabric(4);
  request.output_path = (dir / "s.cbk").string();
  request.stages = {"fabric_records"};
  request.seeds.put("some_stage_options", 42);  // read by no stage: harmless
  const auto result = pipeline::bake(request, stages::bake_stages());
  EXPECT_EQ(result.run.artifacts.get<int>("some_stage_options"), 42);
  pipeline::BakeRequest clash = request;
  clash.seeds = {};
  clash.seeds.put("output", pipeline::OutputRequest{"elsewhere.cbk", false});
  try {
    pipeline::bake(clash, stages::bake_stages());
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ExitCode::Internal);
    EXPECT_NE(std::string(e.what()).find("'output'"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(Artifacts, MergeSharesValuesAndRefusesDuplicates) {
  pipeline::Artifacts a, b;
  a.put("x", 1);
  b.put("y", std::string("two"));
  a.merge(b);
  EXPECT_EQ(a.get<std::string>("y"), "two");
  EXPECT_EQ(&a.get<std::string>("y"), &b.get<std::string>("y")) << "shared, not copied";
  EXPECT_THROW(a.merge(b), Error);
}

}  // namespace
