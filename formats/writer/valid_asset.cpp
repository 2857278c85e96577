// Opening an asset through every validation check (valid_asset.hpp).
#include "formats/writer/valid_asset.hpp"

#include <nlohmann/json.hpp>

#include "common/error.hpp"
#include "formats/validate/validate.hpp"
#include "formats/writer/metadata_json.hpp"
#include "formats/writer/open_asset.hpp"

namespace clothbake::formats {
namespace {

struct FirstError {
  std::string message;
  std::size_t errors = 0;
};

void keep_first_error(void* user, reader::Check check, uint32_t, const char* message) {
  if (reader::is_warning(check)) return;
  auto* first = static_cast<FirstError*>(user);
  if (first->errors++ == 0) first->message = std::string(reader::check_id(check)) + ": " + message;
}

}  // namespace

reader::Asset open_valid_asset(const std::string& path) {
  // Structure only: validate_asset verifies the header and every section checksum itself (a
  // checksummed open would hash every byte a second time).
  reader::Asset asset = open_asset(path, Verify::Structure);
  FirstError first;
  reader::validate_asset(asset, keep_first_error, &first);
  if (first.errors == 0) {
    nlohmann::json metadata;
    for (const auto& f : check_metadata(asset, &metadata))
      keep_first_error(&first, f.check, 0, f.message.c_str());
  }
  if (first.errors > 0)
    throw Error(ExitCode::InvalidAsset,
                path + ": " + first.message +
                    (first.errors > 1 ? " (" + std::to_string(first.errors) +
                                            " errors; clothbake validate lists them)"
                                      : std::string(" (clothbake validate)")));
  return asset;
}

}  // namespace clothbake::formats
