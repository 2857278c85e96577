#include "bake/cli/options.hpp"

#include <cmath>
#include <sstream>

namespace clothbake::cli {

CLI::Option* add_json_flag(CLI::App& app, bool& json, const std::string& help) {
  return app.add_flag("--json", json, help);
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
    try {
      value = rule.integers ? double(std::stoll(item, &used)) : std::stod(item, &used);
    } catch (const std::exception&) {  // not a number, or out of range
      fail();
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
  const std::array<double, 3> d = parse_vec3(text, option);
  if (!(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] > 0))
    throw CLI::ValidationError(option,
                               "'" + text + "' is not a direction: it must be finite and non-zero");
  return d;
}

}  // namespace clothbake::cli
