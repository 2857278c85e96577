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

// Parses `args` (after a program name) with `app`; the ParseError's message, or "".
std::string parse_error_of(CLI::App& app, std::vector<std::string> args) {
  args.insert(args.begin(), "prog");
  std::vector<const char*> argv;
  for (const auto& a : args)
    argv.push_back(a.c_str());
  try {
    app.parse(int(argv.size()), argv.data());
  } catch (const CLI::ParseError& e) {
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

namespace {

// --threads: 0 (the default) means all cores in every command; anything but a whole number in
// [0, 4096] is a usage error that names the option and the text.
TEST(ThreadsOption, ZeroIsAllCoresAndBadValuesNameTheOption) {
  auto parse = [](const std::vector<std::string>& args, int* threads) {
    CLI::App app;
    clothbake::cli::add_threads_option(app, *threads, "worker threads");
    return parse_error_of(app, args);
  };
  int threads = -7;
  EXPECT_EQ(parse({"--threads", "0"}, &threads), "");
  EXPECT_EQ(threads, 0);
  EXPECT_EQ(parse({"--threads", "3"}, &threads), "");
  EXPECT_EQ(threads, 3);
  for (const char* bad : {"-1", "1.5", "x", "4097", "99999999999999999999"}) {
    const std::string message = parse({"--threads", bad}, &threads);
    EXPECT_NE(message.find("--threads"), std::string::npos) << bad << ": " << message;
    EXPECT_NE(message.find(std::string("got '") + bad + "'"), std::string::npos) << message;
    EXPECT_LT(message.size(), 200u) << message;  // no 300-digit range
  }
}

}  // namespace

// --tables: one meaning in eval, render and query (auto = compressed first); unset keeps Auto.
TEST(TablesOption, MapsTheThreeWordsAndRefusesOthers) {
  auto parse = [](const std::vector<std::string>& args, clothbake::eval::TableChoice* choice) {
    CLI::App app;
    clothbake::cli::add_tables_option(app, *choice);
    return parse_error_of(app, args);
  };
  using clothbake::eval::TableChoice;
  TableChoice choice = TableChoice::Auto;
  EXPECT_EQ(parse({}, &choice), "");
  EXPECT_EQ(choice, TableChoice::Auto);
  EXPECT_EQ(parse({"--tables", "raw"}, &choice), "");
  EXPECT_EQ(choice, TableChoice::Raw);
  EXPECT_EQ(parse({"--tables", "compressed"}, &choice), "");
  EXPECT_EQ(choice, TableChoice::Compressed);
  EXPECT_EQ(parse({"--tables", "auto"}, &choice), "");
  EXPECT_EQ(choice, TableChoice::Auto);
  const std::string message = parse({"--tables", "lossy"}, &choice);
  EXPECT_NE(message.find("--tables"), std::string::npos) << message;
  EXPECT_NE(message.find("lossy"), std::string::npos) << message;
}
