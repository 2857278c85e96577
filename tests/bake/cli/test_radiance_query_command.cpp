// The `radiance` kind of `clothbake query` (bake/cli/radiance_query_command.hpp): answers equal the
// reader's, lobes map to their tables, bad arguments are usage errors naming the option.
#include <gtest/gtest.h>

#include "bake/cli/radiance_query_command.hpp"
#include "common/error.hpp"
#include "formats/reader_raw/radiance_tables.hpp"
#include "tests/verify/verify_fixtures.hpp"

using namespace clothbake;

namespace {

struct Opened {
  std::vector<std::byte> bytes;
  reader::Asset asset;
};

std::unique_ptr<Opened> plain_asset(bool gaps) {
  Fabric f = fabric_from_named_weave("plain", 16).fabric;
  // Gaps only where the test wants them (a 16^2 plain weave may not resolve its own).
  for (std::size_t t = 0; t < f.maps.gap.size(); ++t)
    f.maps.gap[t] = gaps && t % 16 == 15 ? 0.0f : 1.0f;
  tables::RadianceOptions o;
  o.bins_per_side = 4;
  o.warn_unresolved = false;
  auto o2 = std::make_unique<Opened>();
  o2->bytes = formats::serialize_asset(verify_testing::asset_sections(f, 3, o));
  EXPECT_TRUE(o2->asset.open_memory(o2->bytes.data(), o2->bytes.size()).ok());
  return o2;
}

ExitCode code_of(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const Error& e) {
    return e.code();
  }
  return ExitCode::Ok;
}

}  // namespace

TEST(RadianceQueryCommand, AnswersEqualTheReaderAndLobesShareTables) {
  auto a = plain_asset(true);
  cli::RadianceQueryArgs args;
  args.lobe = "specular_reflection";
  args.h = {0.3, -0.2, 0.8};
  args.rect = {-3.5, 2.25, 20.0, 9.0};
  const auto all = cli::radiance_query(a->asset, args);
  reader::RawRadianceTables t;
  ASSERT_TRUE(t.open(a->asset, reader::RadianceTableKind::Specular).ok());
  double f[3];
  ASSERT_TRUE(t.query_all({-3.5, 2.25, 20.0, 9.0}, args.h.data(), f).ok());
  ASSERT_EQ(all["clusters"].size(), 3u);
  for (int c = 0; c < 3; ++c)
    EXPECT_DOUBLE_EQ(all["clusters"][c]["F"].get<double>(), f[c]);
  EXPECT_DOUBLE_EQ(all["total"].get<double>(), f[0] + f[1] + f[2]);
  EXPECT_DOUBLE_EQ(all["area_texels"].get<double>(), 23.5 * 6.75);
  // Transmission reads the same table (its own half vector is the caller's business).
  args.lobe = "specular_transmission";
  EXPECT_EQ(cli::radiance_query(a->asset, args)["total"], all["total"]);
  // One cluster.
  args.cluster = 1;
  const auto one = cli::radiance_query(a->asset, args);
  ASSERT_EQ(one["clusters"].size(), 1u);
  EXPECT_DOUBLE_EQ(one["total"].get<double>(), f[1]);
  // Delta transmission reads the gap table; h does not matter there.
  args.lobe = "delta_transmission";
  args.cluster.reset();
  const auto gap = cli::radiance_query(a->asset, args);
  EXPECT_EQ(gap["table"], "gap");
  args.h = {0, 0, -1};
  EXPECT_EQ(cli::radiance_query(a->asset, args)["total"], gap["total"]);
  EXPECT_FALSE(cli::radiance_query_text(gap).empty());
}

TEST(RadianceQueryCommand, BadArgumentsAreUsageErrors) {
  auto a = plain_asset(false);
  cli::RadianceQueryArgs args;
  args.lobe = "specular_reflection";
  auto run = [&](cli::RadianceQueryArgs x) {
    return code_of([&] { cli::radiance_query(a->asset, x); });
  };
  EXPECT_EQ(run(args), ExitCode::Ok);
  auto bad = args;
  bad.lobe = "specular";
  EXPECT_EQ(run(bad), ExitCode::Usage);
  bad.lobe = "sheen";
  EXPECT_EQ(run(bad), ExitCode::Usage);
  bad = args;
  bad.cluster = 3;
  EXPECT_EQ(run(bad), ExitCode::Usage);
  bad = args;
  bad.h = {0, 0, 0};
  EXPECT_EQ(run(bad), ExitCode::Usage);
  bad = args;
  bad.rect = {2, 0, 1, 1};
  EXPECT_EQ(run(bad), ExitCode::Usage);
  bad = args;
  bad.lobe = "delta_transmission";  // no gaps: no gap table
  EXPECT_EQ(run(bad), ExitCode::Input);
}
