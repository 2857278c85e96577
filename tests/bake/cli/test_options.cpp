// bake/cli/options.hpp: the one number-list parser behind every "a,b,c" option (its rules and its
// message), the direction parser, and the --json / ASSET option groups.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "bake/cli/options.hpp"

namespace {

using namespace clothbake::cli;

// The message of the CLI::ValidationError that parsing `text` throws, or "" if it parses.
template <class F>
std::string error_of(F&& parse) {
  try {
    parse();
  } catch (const CLI::ValidationError& e) {
    return e.what();
  }
  return "";
}

TEST(NumberList, SplitsAtCommasAndWhitespace) {
  const NumberListRule any{.expected = "numbers"};
  EXPECT_EQ(parse_number_list("1,2.5,-3e2", "--x", any), (std::vector<double>{1, 2.5, -300}));
  EXPECT_EQ(parse_number_list(" 1, 2 ,3 ", "--x", any), (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(parse_number_list("1 2", "--x", any), (std::vector<double>{1, 2}));
}

TEST(NumberList, RefusesWhatTheRuleForbidsNamingOptionAndText) {
  const NumberListRule pair{.expected = "two integers i,j", .count = 2, .integers = true};
  EXPECT_EQ(error_of([&] { parse_number_list("1.5,2", "--texel", pair); }),
            "--texel: expected two integers i,j, got '1.5,2'");
  EXPECT_NE(error_of([&] { parse_number_list("1,2,3", "--texel", pair); }), "");
  EXPECT_NE(error_of([&] { parse_number_list("1", "--texel", pair); }), "");
  EXPECT_NE(error_of([&] { parse_number_list("", "--texel", pair); }), "");
  EXPECT_NE(error_of([&] { parse_number_list("1,2x", "--texel", pair); }), "");
  const NumberListRule finite{.expected = "numbers"};
  EXPECT_NE(error_of([&] { parse_number_list("1,inf", "--x", finite); }), "");
  EXPECT_NE(error_of([&] { parse_number_list("nan", "--x", finite); }), "");
  EXPECT_NE(error_of([&] { parse_number_list("1e999", "--x", finite); }), "");
  const NumberListRule positive{.expected = "positive numbers", .positive = true};
  EXPECT_NE(error_of([&] { parse_number_list("1,0", "--x", positive); }), "");
  EXPECT_EQ(parse_number_list("0.5,4", "--x", positive), (std::vector<double>{0.5, 4}));
  const NumberListRule ranged{.expected = "two in [2, 8]", .count = 2, .min = 2, .max = 8};
  EXPECT_NE(error_of([&] { parse_number_list("1,8", "--x", ranged); }), "");
  EXPECT_NE(error_of([&] { parse_number_list("2,9", "--x", ranged); }), "");
  EXPECT_EQ(parse_number_list("2,8", "--x", ranged), (std::vector<double>{2, 8}));
}

TEST(Vec3AndDirection, TakeThreeFiniteNumbersAndDirectionsAreNonZero) {
  EXPECT_EQ(parse_vec3("0.3,0.2,0.93", "--dir"), (std::array<double, 3>{0.3, 0.2, 0.93}));
  EXPECT_EQ(error_of([] { parse_vec3("1,2", "--wo"); }),
            "--wo: expected three comma-separated numbers x,y,z, got '1,2'");
  EXPECT_EQ(parse_direction("0,0,2", "--dir"), (std::array<double, 3>{0, 0, 2}));  // not normalised
  EXPECT_EQ(error_of([] { parse_direction("0,0,0", "--wi"); }),
            "--wi: '0,0,0' is not a direction: it must be finite and non-zero");
}

TEST(OptionGroups, JsonFlagAndAssetArgument) {
  CLI::App app;
  bool json = false;
  std::string asset;
  add_json_flag(app, json);
  add_asset_argument(app, asset);
  app.parse(std::vector<std::string>{"a.cbk", "--json"});
  EXPECT_TRUE(json);
  EXPECT_EQ(asset, "a.cbk");
  CLI::App missing;
  std::string none;
  add_asset_argument(missing, none);
  EXPECT_THROW(missing.parse(std::vector<std::string>{}), CLI::RequiredError);
}

}  // namespace
