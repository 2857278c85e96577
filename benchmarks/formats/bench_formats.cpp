// Benchmarks of the asset container (docs/format.md, "Performance"). Run:
//   build-*/bin/bench_formats --benchmark_counters_tabular=true
// The assets are built in memory: the feature maps of an N x N fabric (N = 256, 1024, 2048)
// plus, for the large case, 64 extra 1 MiB sections to exercise the table.
#include <benchmark/benchmark.h>
#include <xxhash.h>

#include <cstring>
#include <map>
#include <random>

#include "compress/map_entropy.hpp"
#include "fabric/fabric_sections.hpp"
#include "formats/reader/asset.hpp"
#include "formats/reader/fabric_sections.hpp"
#include "formats/validate/checksums.hpp"
#include "formats/validate/validate.hpp"
#include "formats/validate/xxh64.hpp"
#include "formats/writer/asset_writer.hpp"
#include "tests/formats/test_fabric.hpp"

namespace {

using namespace clothbake;

std::vector<formats::Section> sections_for(int n, int extra_sections) {
  const Fabric fabric = test_support::make_test_fabric(n);
  auto sections = fabric_record_sections(fabric);
  for (auto& s : compress::feature_map_sections(fabric.maps))
    sections.push_back(std::move(s));
  sections.push_back(formats::make_metadata_section({{"format", "clothbake-asset"}}));
  std::vector<float> block(1 << 18, 0.25f);
  for (int i = 0; i < extra_sections; ++i)
    sections.push_back(formats::make_array_section<float>(reader::SectionType::RadianceRawTables,
                                                          uint32_t(i), block, {512, 512}));
  return sections;
}

// An 8-aligned copy of a serialised asset, cached per size.
const std::vector<uint64_t>& asset_words(int n, std::size_t* size) {
  static std::map<int, std::pair<std::vector<uint64_t>, std::size_t>> cache;
  auto it = cache.find(n);
  if (it == cache.end()) {
    const auto bytes = formats::serialize_asset(sections_for(n, n >= 2048 ? 64 : 0));
    std::vector<uint64_t> words((bytes.size() + 7) / 8);
    std::memcpy(words.data(), bytes.data(), bytes.size());
    it = cache.emplace(n, std::make_pair(std::move(words), bytes.size())).first;
  }
  *size = it->second.second;
  return it->second.first;
}

// Opens the asset of state.range(0) each iteration, then runs verify(asset) (a callable, inlined,
// so that the three benchmarks time the reader and nothing of this loop); returns the asset's
// size in bytes.
template <class Verify>
std::size_t open_loop(benchmark::State& state, Verify verify) {
  std::size_t size;
  const auto& words = asset_words(int(state.range(0)), &size);
  for (auto _ : state) {
    reader::Asset asset;
    auto status = asset.open_memory(words.data(), size);
    if (status.ok()) status = verify(asset);
    if (!status.ok()) state.SkipWithError(status.message());
    benchmark::DoNotOptimize(status);
  }
  state.counters["asset_MB"] = double(size) / 1e6;
  return size;
}

void BM_OpenStructure(benchmark::State& state) {
  open_loop(state, [](const reader::Asset&) { return reader::Status(); });
}
BENCHMARK(BM_OpenStructure)->Arg(256)->Arg(1024)->Arg(2048);

// Open plus the header checksum: what open() did before the checksums became opt-in, and what
// `clothbake info` does.
void BM_OpenAndHeaderChecksum(benchmark::State& state) {
  open_loop(state, [](const reader::Asset& a) { return reader::verify_header_checksum(a); });
}
BENCHMARK(BM_OpenAndHeaderChecksum)->Arg(256)->Arg(1024)->Arg(2048);

void BM_OpenWithChecksums(benchmark::State& state) {
  const std::size_t size =
      open_loop(state, [](const reader::Asset& a) { return reader::verify_checksums(a); });
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(size));
}
BENCHMARK(BM_OpenWithChecksums)->Arg(256)->Arg(1024)->Arg(2048)->Unit(benchmark::kMillisecond);

void BM_ValidateDeep(benchmark::State& state) {
  std::size_t size;
  const auto& words = asset_words(int(state.range(0)), &size);
  reader::Asset asset;
  if (!asset.open_memory(words.data(), size).ok()) state.SkipWithError("open failed");
  for (auto _ : state)
    benchmark::DoNotOptimize(reader::validate_asset(asset, nullptr, nullptr));
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(size));
}
BENCHMARK(BM_ValidateDeep)->Arg(256)->Arg(1024)->Unit(benchmark::kMillisecond);

void BM_FindSection(benchmark::State& state) {
  std::size_t size;
  const auto& words = asset_words(2048, &size);  // 73 sections
  reader::Asset asset;
  if (!asset.open_memory(words.data(), size).ok()) state.SkipWithError("open failed");
  uint32_t instance = 0;
  for (auto _ : state) {
    reader::ArrayView<float> view;
    auto status = asset.array(reader::SectionType::RadianceRawTables, instance, &view);
    benchmark::DoNotOptimize(view.data);
    benchmark::DoNotOptimize(status);
    instance = (instance + 17) & 63;
  }
}
BENCHMARK(BM_FindSection);

void BM_ReadFeatureMaps(benchmark::State& state) {
  std::size_t size;
  const auto& words = asset_words(1024, &size);
  reader::Asset asset;
  if (!asset.open_memory(words.data(), size).ok()) state.SkipWithError("open failed");
  for (auto _ : state) {
    reader::FeatureMaps maps;
    auto status = reader::read_feature_maps(asset, &maps);
    benchmark::DoNotOptimize(maps.height.data);
    benchmark::DoNotOptimize(status);
  }
}
BENCHMARK(BM_ReadFeatureMaps);

void BM_Xxh64Reader(benchmark::State& state) {
  std::vector<unsigned char> data(std::size_t(state.range(0)));
  std::mt19937 rng(1);
  for (auto& b : data)
    b = static_cast<unsigned char>(rng());
  for (auto _ : state)
    benchmark::DoNotOptimize(reader::xxh64(data.data(), data.size(), 0));
  state.SetBytesProcessed(int64_t(state.iterations()) * state.range(0));
}
BENCHMARK(BM_Xxh64Reader)->Arg(64)->Arg(1 << 20)->Arg(1 << 26);

void BM_Xxh64Libxxhash(benchmark::State& state) {
  std::vector<unsigned char> data(std::size_t(state.range(0)));
  std::mt19937 rng(1);
  for (auto& b : data)
    b = static_cast<unsigned char>(rng());
  for (auto _ : state)
    benchmark::DoNotOptimize(XXH64(data.data(), data.size(), 0));
  state.SetBytesProcessed(int64_t(state.iterations()) * state.range(0));
}
BENCHMARK(BM_Xxh64Libxxhash)->Arg(64)->Arg(1 << 20)->Arg(1 << 26);

void BM_Serialize(benchmark::State& state) {
  const auto sections = sections_for(int(state.range(0)), 0);
  const uint64_t size = formats::asset_size(sections);
  for (auto _ : state) {
    auto bytes = formats::serialize_asset(sections);
    benchmark::DoNotOptimize(bytes.data());
  }
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(size));
}
BENCHMARK(BM_Serialize)->Arg(1024)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
