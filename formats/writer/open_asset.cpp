#include "formats/writer/open_asset.hpp"

namespace clothbake::formats {

ExitCode exit_code_of(const reader::Status& status) {
  switch (status.code()) {
    case reader::ErrorCode::Ok:
      return ExitCode::Ok;
    case reader::ErrorCode::Io:
      return ExitCode::Input;
    case reader::ErrorCode::InvalidArgument:
      return ExitCode::Internal;
    case reader::ErrorCode::OutOfPlan:  // a scene-planned asset left out what was asked
      return ExitCode::Input;
    default:
      return ExitCode::InvalidAsset;
  }
}

std::string describe(const reader::Status& status) {
  const std::string id = status.check_id();
  return id.empty() ? status.message() : id + ": " + status.message();
}

void throw_if_failed(const reader::Status& status, const std::string& context) {
  if (status.ok()) return;
  const ExitCode code =
      status.code() == reader::ErrorCode::NotFound ? ExitCode::Input : exit_code_of(status);
  throw Error(code, context + ": " + describe(status));
}

reader::Asset open_asset(const std::string& path, Verify verify) {
  reader::Asset asset;
  reader::Status status = asset.open_file(path.c_str());
  if (status.ok() && verify == Verify::Checksums) {
    status = reader::verify_checksums(asset);
    if (!status.ok()) status.prefix(path.c_str());
  }
  if (!status.ok()) throw Error(exit_code_of(status), describe(status));
  return asset;
}

}  // namespace clothbake::formats
