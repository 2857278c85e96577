// Opens an asset with the installed reader and prints its feature-map resolution and yarn count.
#include <cstdio>

#include <formats/reader/asset.hpp>
#include <formats/reader/fabric_sections.hpp>

int main(int argc, char** argv) {
  if (argc != 2) return 1;
  clothbake::reader::Asset asset;
  clothbake::reader::Status status = asset.open_file(argv[1]);
  if (!status.ok()) {
    std::fprintf(stderr, "%s %s\n", status.check_id(), status.message());
    return 2;
  }
  clothbake::reader::FeatureMaps maps;
  const clothbake::reader::FabricInfoRecord* info = nullptr;
  if (!clothbake::reader::read_feature_maps(asset, &maps).ok() ||
      !clothbake::reader::read_fabric_info(asset, &info).ok())
    return 3;
  std::printf("resolution %u yarns %u\n", unsigned(maps.resolution), unsigned(info->yarn_count));
  return 0;
}
