// Opens an asset with the installed reader, verifies its checksums with the installed opt-in
// validation library, opens its raw tables with the opt-in raw reader when it has any, and prints
// its feature-map resolution and yarn count.
#include <cstdio>

#include <formats/reader/asset.hpp>
#include <formats/reader/fabric_sections.hpp>
#include <formats/reader_raw/radiance_tables.hpp>
#include <formats/validate/checksums.hpp>

int main(int argc, char** argv) {
  if (argc != 2) return 1;
  clothbake::reader::Asset asset;
  clothbake::reader::Status status = asset.open_file(argv[1]);
  if (status.ok()) status = clothbake::reader::verify_checksums(asset);
  if (!status.ok()) {
    std::fprintf(stderr, "%s %s\n", status.check_id(), status.message());
    return 2;
  }
  clothbake::reader::FeatureMaps maps;
  const clothbake::reader::FabricInfoRecord* info = nullptr;
  if (!clothbake::reader::read_feature_maps(asset, &maps).ok() ||
      !clothbake::reader::read_fabric_info(asset, &info).ok())
    return 3;
  clothbake::reader::RawRadianceTables raw;
  status = raw.open(asset, clothbake::reader::RadianceTableKind::Specular);
  if (!status.ok() && status.code() != clothbake::reader::ErrorCode::NotFound) return 4;
  std::printf("resolution %u yarns %u\n", unsigned(maps.resolution), unsigned(info->yarn_count));
  return 0;
}
