#include "bake/cli/options.hpp"

#include "bake/cache/stage_cache.hpp"
#include "bake/pipeline/resource_usage.hpp"
#include "common/error.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <map>
#include <sstream>

namespace clothbake::cli {

CLI::Option* add_json_flag(CLI::App& app, bool& json, const std::string& help) {
  return app.add_flag("--json", json, help);
}

CLI::Option* add_tables_option(CLI::App& app, eval::TableChoice& choice, const std::string& scope) {
  return app
      .add_option_function<std::string>(
          "--tables",
          [&choice](const std::string& word) {
            choice = word == "raw"          ? eval::TableChoice::Raw
                     : word == "compressed" ? eval::TableChoice::Compressed
                                            : eval::TableChoice::Auto;
          },
          scope +
              "Integral-Radiance tables: auto (the compressed ones when the asset has them, else "
              "the raw ones; the default), raw, compressed")
      ->check(CLI::IsMember({"auto", "raw", "compressed"}))
      ->option_text("auto|raw|compressed");
}

std::array<int, 2> parse_image_size(const std::string& text) {
  NumberListRule rule;
  rule.expected = "W,H (integers in [1, 16384])";
  rule.count = 2;
  rule.integers = true;
  rule.min = 1;
  rule.max = 16384;
  const std::vector<double> wh = parse_number_list(text, "--image-size", rule);
  return {int(wh[0]), int(wh[1])};
}

CLI::Option* add_threads_option(CLI::App& app, int& threads, const std::string& help) {
  // The project's number parser, as a CLI11 validator (its message without the option prefix,
  // which CLI11 adds).
  const CLI::Validator whole_non_negative(
      [](std::string& text) -> std::string {
        const NumberListRule rule{.expected = "a whole number in [0, 4096] (0: all cores)",
                                  .count = 1,
                                  .integers = true,
                                  .min = 0,
                                  .max = 4096};
        try {
          (void)parse_number_list(text, "", rule);
        } catch (const CLI::ValidationError&) {
          return "must be " + rule.expected + ", got '" + text + "'";
        }
        return {};
      },
      "N >= 0");
  return app.add_option("--threads", threads, help + " (0, the default: all cores)")
      ->check(whole_non_negative);
}

CLI::Option* add_asset_argument(CLI::App& app, std::string& path, const std::string& help) {
  return app.add_option("ASSET", path, help)->required();
}

std::vector<double> parse_number_list(const std::string& text, const std::string& option,
                                      const NumberListRule& rule) {
  auto fail = [&] {
    throw CLI::ValidationError(option, "expected " + rule.expected + ", got '" + text + "'");
  };
  std::string spaced = text;
  for (char& ch : spaced)
    if (ch == ',') ch = ' ';
  std::istringstream in(spaced);
  std::vector<double> values;
  std::string item;
  while (in >> item) {
    std::size_t used = 0;
    double value = 0;
    if (rule.integers) {
      try {
        value = double(std::stoll(item, &used));
      } catch (const std::exception&) {  // not a number, or out of range
        fail();
      }
    } else {
      // strtod, not stod: a subnormal such as 1e-310 is a number (stod throws on the underflow);
      // an overflow (1e999) is not.
      char* end = nullptr;
      errno = 0;
      value = std::strtod(item.c_str(), &end);
      used = std::size_t(end - item.c_str());
      if (errno == ERANGE && std::fabs(value) >= 1.0) fail();
    }
    if (used != item.size() || !std::isfinite(value) || (rule.positive && !(value > 0)) ||
        value < rule.min || value > rule.max)
      fail();
    values.push_back(value);
  }
  if (values.empty() || (rule.count != 0 && values.size() != rule.count)) fail();
  return values;
}

std::array<double, 3> parse_vec3(const std::string& text, const std::string& option) {
  const auto v = parse_number_list(text, option,
                                   {.expected = "three comma-separated numbers x,y,z", .count = 3});
  return {v[0], v[1], v[2]};
}

std::array<double, 3> parse_direction(const std::string& text, const std::string& option) {
  std::array<double, 3> d = parse_vec3(text, option);
  const double largest = std::max({std::fabs(d[0]), std::fabs(d[1]), std::fabs(d[2])});
  if (!(largest > 0))
    throw CLI::ValidationError(option,
                               "'" + text + "' is not a direction: it must be finite and non-zero");
  // Outside [1e-150, 1e150] the squared length would overflow (1e308,1e308,1e308) or underflow
  // (1e-310,0,1e-310) downstream: such a vector is divided by its largest component (the same
  // direction). Others are returned as given.
  if (largest > 1e150 || largest < 1e-150)
    for (double& c : d)
      c /= largest;
  return d;
}

uint64_t max_memory_option(const std::string& text, double default_share) {
  if (text.empty()) return uint64_t(double(pipeline::machine_memory_bytes()) * default_share);
  const uint64_t bytes = cache::parse_size(text, "--max-memory");
  if (bytes == 0)
    throw Error(ExitCode::Usage, "--max-memory must be above 0 bytes, got '" + text + "'");
  return bytes;
}

}  // namespace clothbake::cli
