// Parallax sections: layout checks and queries (parallax_sections.hpp).
#include "formats/reader/parallax_sections.hpp"

#include <cmath>
#include <cstring>

#include "formats/reader/detail/open_sections.hpp"
#include "formats/reader/parallax_entropy.hpp"
#include "formats/reader/parallax_hierarchy.hpp"
#include "formats/reader/scene_plan_sections.hpp"
#include "model/directions.hpp"
#include "model/tile.hpp"

namespace clothbake::reader {
namespace {

constexpr uint64_t kTwo32 = uint64_t(1) << 32;

}  // namespace

// The compressed form's decoded planes and on-demand SATs: per direction one u16 plane and one
// u32 inclusive SAT (the ParallaxSat layout), each built once under its flag and published
// through its atomic pointer.
struct ParallaxView::Packed {
  explicit Packed(const model::Allocator* memory) noexcept : allocator(memory) {}
  ~Packed() {
    for (uint64_t d = 0; d < count; ++d) {
      release(sats[d].load(std::memory_order_relaxed));
      release(planes16[d].load(std::memory_order_relaxed));
    }
  }
  Packed(const Packed&) = delete;
  Packed& operator=(const Packed&) = delete;

  // The per-direction flags and pointers (all null); false when the memory cannot be had.
  bool allocate_directory(uint64_t dirs) noexcept {
    if (!flags.allocate(dirs, allocator) || !sats.allocate(dirs, allocator) ||
        !plane_flags.allocate(dirs, allocator) || !planes16.allocate(dirs, allocator))
      return false;
    for (uint64_t d = 0; d < dirs; ++d) {
      sats[d].store(nullptr, std::memory_order_relaxed);
      planes16[d].store(nullptr, std::memory_order_relaxed);
    }
    count = dirs;
    return true;
  }
  // `n` values of T from the asset's allocator (n <= 16384^2: no overflow), or null.
  template <class T>
  T* allocate(uint64_t n) const noexcept {
    return static_cast<T*>(allocator->allocate(allocator->user, std::size_t(n) * sizeof(T), 8));
  }
  void release(void* pointer) const noexcept {
    if (pointer != nullptr) allocator->release(allocator->user, pointer);
  }

  const model::Allocator* allocator;
  std::atomic<uint64_t> references{1};  // SharedPacked handles
  uint64_t count = 0;
  model::Buffer<std::once_flag> flags;
  model::Buffer<std::atomic<uint32_t*>> sats;
  model::Buffer<std::once_flag> plane_flags;
  model::Buffer<std::atomic<uint16_t*>> planes16;
  std::atomic<uint64_t> bytes{0};
};

ParallaxView::SharedPacked::SharedPacked(const SharedPacked& other) noexcept : p_(other.p_) {
  if (p_ != nullptr) p_->references.fetch_add(1, std::memory_order_relaxed);
}

ParallaxView::SharedPacked::~SharedPacked() {
  if (p_ != nullptr && p_->references.fetch_sub(1, std::memory_order_acq_rel) == 1)
    model::destroy_object(*p_->allocator, p_);
}

namespace {
// Any section of `type` with an instance below `instances`.
bool any_instance(const Asset& asset, SectionType type, uint32_t instances) noexcept {
  for (uint32_t i = 0; i < instances; ++i) {
    SectionInfo unused;
    if (asset.find(type, i, &unused).ok()) return true;
  }
  return false;
}
}  // namespace

Status ParallaxView::open(const Asset& asset, ParallaxSource source) noexcept {
  *this = ParallaxView();
  Status s;
  const bool coded = any_instance(asset, SectionType::ParallaxEntropy, 6);
  if (source == ParallaxSource::Compressed) {
    s = open_coded(asset);
  } else {
    s = open_raw(asset);
    if (source == ParallaxSource::Auto && s.code() == ErrorCode::NotFound && coded)
      s = open_coded(asset);
  }
  if (!s.ok()) *this = ParallaxView();
  exact_sums_ = s.ok() && 65535u * uint64_t(info_.resolution) * info_.resolution < kTwo32;
  return s;
}

#ifndef CLOTHBAKE_SINGLE_FILE
uint64_t ParallaxView::decoded_bytes() const noexcept {
  return packed_ ? packed_->bytes.load(std::memory_order_relaxed) : 0;
}
#endif

double ParallaxView::depth_step(uint32_t bin) const noexcept {
  if (!covers(bin)) return 0.0;
  return steps_ ? steps_[bin] : info_.depth_scale;
}

namespace {
// The range checks of a CompressedParallaxInfoRecord.
Status check_compressed_record(const CompressedParallaxInfoRecord& info,
                               const char* name) noexcept {
  if (info.resolution < 1 || info.resolution > kMaxParallaxResolution || info.dirs < 1 ||
      info.dirs > kMaxParallaxDirs)
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "%s: resolution %u or directions %u out of range (1..%u, 1..%u)", name,
                         unsigned(info.resolution), unsigned(info.dirs),
                         unsigned(kMaxParallaxResolution), unsigned(kMaxParallaxDirs));
  if (!(info.min_cos >= 0.0 && info.min_cos < 1.0) || !std::isfinite(info.reference_height) ||
      !(info.max_offset >= 0.0 && std::isfinite(info.max_offset)) ||
      !(info.rms_offset_error >= 0.0 && std::isfinite(info.rms_offset_error)) ||
      !(info.max_offset_error >= 0.0 && std::isfinite(info.max_offset_error)) ||
      !(info.max_depth_error >= 0.0 && std::isfinite(info.max_depth_error)))
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "%s: min_cos, reference height, max offset or an error out of range",
                         name);
  return {};
}

// A planned table's view directions: bin_map instance 1, which must be present. `what` names the
// section in the error.
Status read_view_bin_map(const Asset& asset, uint32_t dirs, const char* what,
                         BinMapView* map) noexcept {
  const Status s = read_bin_map(asset, kViewBinMap, dirs, map);
  if (!s.ok()) return s;
  if (!map->present())
    return Status::error(ErrorCode::NotFound, Check::MissingSection,
                         "%s: a planned table needs bin_map instance 1 (its view directions)",
                         what);
  return Status();
}

Status check_steps(const ArrayView<double>& steps, uint64_t d, const char* name) noexcept {
  if (steps.rank != 1 || steps.dims[0] != d)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "%s instance 1 must be f64 {%llu} (one step per direction)", name,
                         static_cast<unsigned long long>(d));
  for (uint64_t i = 0; i < d; ++i)
    if (!(steps.data[i] >= 0.0 && steps.data[i] <= 1.0))  // also NaN
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "%s: step of direction %llu is not in [0, 1] tile-side units", name,
                           static_cast<unsigned long long>(i));
  return {};
}
}  // namespace

// Largest total of decoded planes the entropy form may describe (D * N^2 bytes): 4 GiB.
constexpr uint64_t kMaxEntropyDecodedBytes = uint64_t(1) << 32;

Status ParallaxView::open_coded(const Asset& asset) noexcept {
  const char* name = "parallax_entropy";
  const char* missing =
      "this asset has no compressed parallax table (parallax_entropy instances 0 to 5)";
  const char* version_message =
      "parallax_entropy: payload version must be 1 (this reader knows version 1, the same for "
      "every instance)";
  const uint32_t bits = 16;
  const uint32_t contexts = uint32_t(kHierContexts);
  const uint16_t version = kHierParallaxVersion;
  ArrayView<uint8_t> info_bytes;
  ArrayView<double> steps;
  Status s = detail::view_required_pair(
      asset, {SectionType::ParallaxEntropy, kEntropyParallaxInfoInstance},
      {SectionType::ParallaxEntropy, kEntropyParallaxStepsInstance}, missing, version_message,
      &info_bytes, &steps, version);
  if (!s.ok()) return s;
  if (info_bytes.rank != 2 || info_bytes.dims[0] != 1 ||
      info_bytes.dims[1] != sizeof(CompressedParallaxInfoRecord))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "parallax_entropy instance 0 must be u8 {1, 64} (one "
                         "CompressedParallaxInfoRecord)");
  CompressedParallaxInfoRecord info;
  std::memcpy(&info, info_bytes.data, sizeof info);
  // flags: 0, or kEntropyPlannedFlag (a scene-planned asset, coverage in bin map 1).
  if ((info.flags & ~kEntropyPlannedFlag) != 0 || info.bits != bits)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout,
                         "%s: bits %u / flags %u unknown to this reader (version %u has %u / 0 "
                         "or 1)",
                         name, unsigned(info.bits), unsigned(info.flags), unsigned(version),
                         unsigned(bits));
  const bool planned = (info.flags & kEntropyPlannedFlag) != 0;
  s = check_compressed_record(info, name);
  if (!s.ok()) return s;
  const uint64_t n = info.resolution, d = uint64_t(info.dirs) * info.dirs;
  s = check_steps(steps, d, name);
  if (!s.ok()) return s;
  ArrayView<uint64_t> offsets;
  ArrayView<uint8_t> stream;
  s = detail::view_required_pair(asset,
                                 {SectionType::ParallaxEntropy, kEntropyParallaxOffsetsInstance},
                                 {SectionType::ParallaxEntropy, kEntropyParallaxStreamInstance},
                                 missing, version_message, &offsets, &stream, version);
  if (!s.ok()) return s;
  if (offsets.rank != 1 || offsets.dims[0] != d + 1 || stream.rank != 1)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "parallax_entropy instance 2 must be u64 {%llu} (block offsets) and "
                         "instance 3 u8 {bytes}",
                         static_cast<unsigned long long>(d + 1));
  if (offsets.data[0] != 0 || offsets.data[d] != stream.dims[0])
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "parallax_entropy: block offsets must run from 0 to the stream's size "
                         "%llu",
                         static_cast<unsigned long long>(stream.dims[0]));
  for (uint64_t i = 0; i < d; ++i)
    if (offsets.data[i + 1] < offsets.data[i])
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "parallax_entropy: block offsets decrease at direction %llu",
                           static_cast<unsigned long long>(i));
  ArrayView<uint16_t> tables;
  bool have_tables = false;
  s = detail::view_optional(asset, {SectionType::ParallaxEntropy, kEntropyParallaxTablesInstance},
                            version_message, &tables, &have_tables, version);
  if (!s.ok()) return s;
  if (!have_tables) return Status::error(ErrorCode::NotFound, Check::MissingSection, "%s", missing);
  if (tables.rank != 3 || tables.dims[0] < 1 || tables.dims[0] > kMaxEntropyGroups ||
      tables.dims[1] != contexts || tables.dims[2] != 256)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "parallax_entropy instance 4 must be u16 {groups, %u, 256} with 1 to "
                         "65536 groups (payload version %u)",
                         unsigned(contexts), unsigned(version));
  for (uint32_t g = 0; g < tables.dims[0]; ++g) {
    const uint16_t* group_tables = tables.data + uint64_t(g) * contexts * 256;
    const Status t = check_hierarchical_tables(group_tables);
    if (!t.ok())
      return Status::error(ErrorCode::Malformed, Check::ValueRange, "group %u: %s", unsigned(g),
                           t.message());
  }
  ArrayView<uint32_t> weights;
  {
    bool have_weights = false;
    s = detail::view_optional(asset, {SectionType::ParallaxEntropy, kHierParallaxWeightsInstance},
                              version_message, &weights, &have_weights, version);
    if (!s.ok()) return s;
    if (!have_weights)
      return Status::error(ErrorCode::NotFound, Check::MissingSection, "%s", missing);
    if (weights.rank != 1 || weights.dims[0] != d)
      return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                           "parallax_entropy instance 5 must be u32 {%llu} (one prediction "
                           "weight per direction)",
                           static_cast<unsigned long long>(d));
    for (uint64_t i = 0; i < d; ++i)
      if (weights.data[i] < 1 || weights.data[i] > kMaxHierWeight)
        return Status::error(ErrorCode::Malformed, Check::ValueRange,
                             "parallax_entropy: prediction weight of direction %llu is not in "
                             "[1, 2^24]",
                             static_cast<unsigned long long>(i));
  }
  if (d * n * n * 2 > kMaxEntropyDecodedBytes)
    return Status::error(ErrorCode::Unsupported, Check::ResourceLimit,
                         "parallax_entropy: %llu directions of %llu^2 codes would decode to more "
                         "than 4 GiB",
                         static_cast<unsigned long long>(d), static_cast<unsigned long long>(n));
  // Which directions are stored: all, or (planned) those of bin map 1; a block is empty exactly
  // when its direction is not stored. Hierarchical: a stored direction's references are stored.
  BinMapView map;
  if (planned) {
    s = read_view_bin_map(asset, info.dirs, "parallax_entropy", &map);
    if (!s.ok()) return s;
  }
  for (uint64_t i = 0; i < d; ++i) {
    const bool stored = !planned || map.covers(uint32_t(i));
    const bool empty = offsets.data[i + 1] == offsets.data[i];
    if (empty == stored)
      return Status::error(ErrorCode::Malformed, Check::ValueRange,
                           "parallax_entropy: direction %llu is %s but its block is %s",
                           static_cast<unsigned long long>(i),
                           stored ? "stored" : "left out of bin_map instance 1",
                           empty ? "empty" : "not empty");
    if (!planned || !stored) continue;
    const ParallaxReferences refs =
        parallax_references(uint32_t(i % info.dirs), uint32_t(i / info.dirs), info.dirs);
    for (int e = 0; e < refs.count; ++e)
      if (!map.covers(refs.bin[e]))
        return Status::error(ErrorCode::Malformed, Check::ValueRange,
                             "parallax_entropy: direction %llu is stored but direction %u, which "
                             "it is predicted from, is left out of bin_map instance 1",
                             static_cast<unsigned long long>(i), unsigned(refs.bin[e]));
  }
  SharedPacked packed(model::create_object<Packed>(*asset.allocator(), asset.allocator()));
  if (!packed || !packed->allocate_directory(d))
    return Status::error(ErrorCode::Unsupported, Check::None,
                         "parallax_entropy: cannot allocate the block directory");
  if (planned) covered_ = map.mask;  // in the asset's bytes, which outlive the view
  info_ = ParallaxInfoRecord{};
  info_.resolution = info.resolution;
  info_.dirs = info.dirs;
  info_.min_cos = info.min_cos;
  info_.reference_height = info.reference_height;
  info_.max_quantization_error = info.max_depth_error;
  info_.max_offset = info.max_offset;
  packed_info_ = info;
  steps_ = steps.data;
  offsets_ = offsets.data;
  tables_ = tables.data;
  groups_ = tables.dims[0];
  weights_ = weights.data;
  stream_ = stream.data != nullptr ? stream.data : reinterpret_cast<const uint8_t*>("");
  packed_ = std::move(packed);
  return {};
}

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
bool ParallaxView::ensure_plane(uint32_t bin) const noexcept {
  if (stream_ == nullptr) return true;
  if (!covers(bin)) return false;  // planned: the direction was left out
  return plane16(bin) != nullptr;
}
#endif

const uint16_t* ParallaxView::bin_codes(uint32_t bin) const noexcept {
  if (!covers(bin)) return nullptr;
  if (codes_) return codes_ + uint64_t(bin) * info_.resolution * info_.resolution;
  return packed_ ? plane16(bin) : nullptr;
}

namespace {
// Decodes the hierarchical block of `bin` into `plane` with its references' decoded planes (the
// caller decoded them; a null one is read as zeros through `zeros`).
Status decode_hierarchical_bin(const uint8_t* stream, const uint64_t* offsets,
                               const uint16_t* tables, uint32_t groups, const uint32_t* weights,
                               uint32_t dirs, uint32_t n, uint32_t bin,
                               const uint16_t* const ref_planes[4], uint16_t* plane, int32_t* diff,
                               ParallaxHierScratch* scratch) noexcept {
  const ParallaxReferences refs = parallax_references(bin % dirs, bin / dirs, dirs);
  uint32_t ref_m[4] = {1, 1, 1, 1};
  for (int e = 0; e < refs.count; ++e)
    ref_m[e] = weights[refs.bin[e]];
  return decode_hierarchical_block(stream + offsets[bin], offsets[bin + 1] - offsets[bin], tables,
                                   groups, n, weights[bin], ref_planes, ref_m, refs.count, plane,
                                   diff, scratch);
}
}  // namespace

const uint16_t* ParallaxView::plane16(uint32_t bin) const noexcept {
  Packed& p = *packed_;
  const uint16_t* ready = p.planes16[bin].load(std::memory_order_acquire);
  if (ready) return ready;
  std::call_once(p.plane_flags[bin], [&] {
    const uint32_t dirs = info_.dirs;
    const ParallaxReferences refs = parallax_references(bin % dirs, bin / dirs, dirs);
    const uint16_t* ref_planes[4] = {nullptr, nullptr, nullptr, nullptr};
    for (int e = 0; e < refs.count; ++e)  // lower levels first (at most two deep)
      if ((ref_planes[e] = plane16(refs.bin[e])) == nullptr) return;
    const uint64_t n = info_.resolution;
    uint16_t* plane = p.allocate<uint16_t>(n * n);
    model::Buffer<int32_t> diff;
    model::Buffer<ParallaxHierScratch> scratch;
    if (!plane || !diff.allocate(n * n, p.allocator) || !scratch.allocate(1, p.allocator)) {
      p.release(plane);
      return;
    }
    // A block that does not decode exactly is zero-filled by the decoder (decode_all says so).
    (void)decode_hierarchical_bin(stream_, offsets_, tables_, groups_, weights_, dirs, uint32_t(n),
                                  bin, ref_planes, plane, diff.get(), scratch.get());
    p.bytes.fetch_add(n * n * 2, std::memory_order_relaxed);
    p.planes16[bin].store(plane, std::memory_order_release);
  });
  return p.planes16[bin].load(std::memory_order_acquire);
}

Status ParallaxView::decode_all() const noexcept {
  if (stream_ == nullptr) return {};
  const uint64_t n = info_.resolution, d = uint64_t(info_.dirs) * info_.dirs;
  model::Buffer<uint16_t> plane;
  model::Buffer<int32_t> diff;
  model::Buffer<ParallaxHierScratch> scratch;
  const model::Allocator* allocator = packed_->allocator;
  if (!plane.allocate(n * n, allocator) || !diff.allocate(n * n, allocator) ||
      !scratch.allocate(1, allocator))
    return Status::error(ErrorCode::Unsupported, Check::None,
                         "parallax_entropy: cannot allocate a plane to decode");
  for (uint64_t i = 0; i < d; ++i) {
    if (!covers(uint32_t(i))) continue;  // planned: an empty block (open checked it)
    const ParallaxReferences refs =
        parallax_references(uint32_t(i % info_.dirs), uint32_t(i / info_.dirs), info_.dirs);
    const uint16_t* ref_planes[4] = {nullptr, nullptr, nullptr, nullptr};
    for (int e = 0; e < refs.count; ++e)
      if ((ref_planes[e] = plane16(refs.bin[e])) == nullptr)
        return Status::error(ErrorCode::Unsupported, Check::None,
                             "parallax_entropy: cannot allocate the planes direction %llu "
                             "references",
                             static_cast<unsigned long long>(i));
    const Status s = decode_hierarchical_bin(stream_, offsets_, tables_, groups_, weights_,
                                             info_.dirs, uint32_t(n), uint32_t(i), ref_planes,
                                             plane.get(), diff.get(), scratch.get());
    if (!s.ok())
      return Status::error(ErrorCode::Malformed, Check::ValueRange, "direction %llu: %s",
                           static_cast<unsigned long long>(i), s.message());
  }
  return {};
}

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
uint32_t ParallaxView::stored_dirs() const noexcept {
  if (!covered_) return info_.dirs * info_.dirs;
  uint32_t k = 0;
  for (uint32_t b = 0; b < info_.dirs * info_.dirs; ++b)
    k += covered_[b] != 0 ? 1u : 0u;
  return k;
}
#endif

Status ParallaxView::out_of_plan(int bin) const noexcept {
  return Status::error(ErrorCode::OutOfPlan, Check::None,
                       "parallax: view direction bin %d was left out of this scene-planned asset "
                       "(bin_map instance 1)",
                       bin);
}

bool ParallaxView::ensure_sat(uint32_t bin) const noexcept {
  if (!packed_) return true;
  if (!covers(bin)) return false;  // planned: the direction was left out
  if (packed_->sats[bin].load(std::memory_order_acquire) != nullptr) return true;  // built
  const uint16_t* decoded = plane16(bin);
  if (decoded == nullptr) return false;
  Packed& p = *packed_;
  std::call_once(p.flags[bin], [&] {
    const uint64_t n = info_.resolution;
    uint32_t* sat = p.allocate<uint32_t>(n * n);
    if (!sat) return;  // stays null: the query reports it
    for (uint64_t y = 0; y < n; ++y) {
      uint32_t row = 0;  // wraps modulo 2^32 (exact differences, as for ParallaxSat)
      for (uint64_t x = 0; x < n; ++x) {
        row += uint32_t(decoded[y * n + x]);
        sat[y * n + x] = row + (y > 0 ? sat[(y - 1) * n + x] : 0u);
      }
    }
    p.bytes.fetch_add(n * n * 4, std::memory_order_relaxed);
    p.sats[bin].store(sat, std::memory_order_release);
  });
  return p.sats[bin].load(std::memory_order_acquire) != nullptr;
}

const uint32_t* ParallaxView::bin_sat(uint32_t bin) const noexcept {
  if (!packed_) return sat_ + uint64_t(bin) * info_.resolution * info_.resolution;
  return packed_->sats[bin].load(std::memory_order_acquire);
}

Status ParallaxView::open_raw(const Asset& asset) noexcept {
#ifdef CLOTHBAKE_SINGLE_FILE
  (void)asset;
  return Status::error(ErrorCode::NotFound, Check::MissingSection,
                       "the single-file build reads the compressed parallax only");
#else
  ArrayView<uint8_t> info_bytes;
  ArrayView<uint16_t> codes;
  Status s = detail::view_required_pair(
      asset, {SectionType::ParallaxTable, kParallaxInfoInstance},
      {SectionType::ParallaxTable, kParallaxCodesInstance},
      "this asset has no parallax table (parallax instances 0 and 1)",
      "parallax: payload version must be 1 (this reader knows version 1)", &info_bytes, &codes);
  if (!s.ok()) return s;
  if (info_bytes.rank != 2 || info_bytes.dims[0] != 1 ||
      info_bytes.dims[1] != sizeof(ParallaxInfoRecord))
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "parallax instance 0 must be u8 {1, 64} (one ParallaxInfoRecord)");
  ParallaxInfoRecord info;
  std::memcpy(&info, info_bytes.data, sizeof info);
  for (unsigned char b : info.reserved)
    if (b != 0)
      return Status::error(ErrorCode::Malformed, Check::Padding,
                           "parallax: reserved bytes of the info record are not zero");
  if (info.resolution < 1 || info.resolution > kMaxParallaxResolution || info.dirs < 1 ||
      info.dirs > kMaxParallaxDirs)
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "parallax: resolution %u or directions %u out of range (1..%u, 1..%u)",
                         unsigned(info.resolution), unsigned(info.dirs),
                         unsigned(kMaxParallaxResolution), unsigned(kMaxParallaxDirs));
  if (!(info.min_cos >= 0.0 && info.min_cos < 1.0) || !std::isfinite(info.reference_height) ||
      !(info.depth_scale >= 0.0 && std::isfinite(info.depth_scale)) ||
      !(info.max_quantization_error >= 0.0 && std::isfinite(info.max_quantization_error)) ||
      !(info.max_offset >= 0.0 && std::isfinite(info.max_offset)))
    return Status::error(ErrorCode::Malformed, Check::ValueRange,
                         "parallax: min_cos, reference height, depth scale or error out of range");
  const uint64_t n = info.resolution, d = uint64_t(info.dirs) * info.dirs;
  if (codes.rank != 3 || codes.dims[0] != d || codes.dims[1] != n || codes.dims[2] != n)
    return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                         "parallax instance 1 must be u16 {%llu, %llu, %llu} (directions, N, N)",
                         static_cast<unsigned long long>(d), static_cast<unsigned long long>(n),
                         static_cast<unsigned long long>(n));
  const uint32_t* sat = nullptr;
  ArrayView<uint32_t> sat_view;
  bool have_sat = false;
  s = detail::view_optional(asset, {SectionType::ParallaxSat, 0},
                            "parallax_sat: payload version must be 1", &sat_view, &have_sat);
  if (!s.ok()) return s;
  if (have_sat) {
    if (sat_view.rank != 3 || sat_view.dims[0] != d || sat_view.dims[1] != n ||
        sat_view.dims[2] != n)
      return Status::error(ErrorCode::WrongType, Check::SectionLayout,
                           "parallax_sat must be u32 with the parallax table's shape {%llu, %llu, "
                           "%llu}",
                           static_cast<unsigned long long>(d), static_cast<unsigned long long>(n),
                           static_cast<unsigned long long>(n));
    sat = sat_view.data;
  }
  info_ = info;
  codes_ = codes.data;
  sat_ = sat;
  return {};
#endif
}

uint32_t ParallaxView::bin_code(uint32_t bin, int64_t x, int64_t y) const noexcept {
  const int64_t n = info_.resolution;
  return code(bin,
              uint64_t(model::wrap_index(y, n)) * uint64_t(n) + uint64_t(model::wrap_index(x, n)));
}

double ParallaxView::bin_depth(uint32_t bin, int64_t x, int64_t y) const noexcept {
  const int64_t n = info_.resolution;
  if (!covers(bin)) return 0.0;
  const uint64_t index =
      uint64_t(model::wrap_index(y, n)) * uint64_t(n) + uint64_t(model::wrap_index(x, n));
  return -double(code(bin, index)) * depth_step(bin);
}

Status ParallaxView::view_direction(const double view[3], double o[3]) const noexcept {
  if (view == nullptr || !std::isfinite(view[0]) || !std::isfinite(view[1]) ||
      !std::isfinite(view[2]))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "view direction must have finite components");
  const double len = std::sqrt(view[0] * view[0] + view[1] * view[1] + view[2] * view[2]);
  if (!(len > 0.0) || !std::isfinite(len))
    return Status::error(ErrorCode::InvalidArgument, Check::None,
                         "view direction must be non-zero");
  o[0] = view[0] / len;
  o[1] = view[1] / len;
  o[2] = view[2] / len;
  if (o[2] < info_.min_cos) {  // onto the rim of the cap, same azimuth
    double planar = std::sqrt(o[0] * o[0] + o[1] * o[1]);
    double ax = planar > 0.0 ? o[0] / planar : 1.0, ay = planar > 0.0 ? o[1] / planar : 0.0;
    double s = std::sqrt(1.0 - info_.min_cos * info_.min_cos);
    o[0] = ax * s;
    o[1] = ay * s;
    o[2] = info_.min_cos;
  }
  return {};
}

double ParallaxView::weighted_depth(const int bin[4], const double weight[4], int64_t x,
                                    int64_t y) const noexcept {
  const uint64_t n = info_.resolution;
  const uint64_t texel =
      uint64_t(model::wrap_index(y, int64_t(n))) * n + uint64_t(model::wrap_index(x, int64_t(n)));
  double r = 0.0;
  if (stream_) {
    for (int k = 0; k < 4; ++k)
      if (weight[k] > 0.0 && covers(uint32_t(bin[k]))) {  // uncovered bins count 0
        const uint16_t* p = plane16(uint32_t(bin[k]));
        if (p) r += weight[k] * (-double(p[texel]) * steps_[bin[k]]);
      }
    return r;
  }
  for (int k = 0; k < 4; ++k)
    if (weight[k] > 0.0)
      r += weight[k] * (-double(codes_[uint64_t(bin[k]) * n * n + texel]) * info_.depth_scale);
  return r;
}

Status ParallaxView::depth(int64_t x, int64_t y, const double view[3],
                           ParallaxSample* out) const noexcept {
  if (!is_open() || out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "parallax view is not open");
  double o[3];
  Status s = view_direction(view, o);
  if (!s.ok()) return s;
  const model::DirectionGrid<double> grid{int(info_.dirs), info_.min_cos};
  const model::BinBilinear<double> w = grid.bilinear_fast(model::Vec3d(o[0], o[1], o[2]));
  for (int k = 0; k < 4; ++k)
    if (w.weight[k] > 0.0 && !covers(uint32_t(w.index[k]))) return out_of_plan(w.index[k]);
  // One wrap of (x, y) for the four bins (weighted_depth).
  const double r = weighted_depth(w.index, w.weight, x, y);
  out->r = r;
  out->offset[0] = r / o[2] * o[0];
  out->offset[1] = r / o[2] * o[1];
  for (int i = 0; i < 3; ++i)
    out->direction[i] = o[i];
  return {};
}

#ifndef CLOTHBAKE_SINGLE_FILE  // used by the tools, not by shading
uint64_t ParallaxView::code_prefix_sum(uint32_t bin, uint32_t x, uint32_t y) const noexcept {
  return prefix_sum_of(bin_sat(bin), x, y);
}
#endif

uint64_t ParallaxView::prefix_sum_of(const uint32_t* table, uint32_t x, uint32_t y) const noexcept {
  if (x == 0 || y == 0 || table == nullptr) return 0;
  const uint64_t n = info_.resolution;
  auto s = [&](uint64_t i, uint64_t j) -> uint32_t {  // exclusive prefix, modulo 2^32
    return (i == 0 || j == 0) ? 0u : table[(j - 1) * n + (i - 1)];
  };
  // A rectangle of x * rows texels sums to at most 65535 * x * rows: below 2^32 it is exact (the
  // common case: always for N <= 256).
  if (65535u * uint64_t(x) * y < kTwo32) return s(x, y);
  const uint64_t rows = (kTwo32 - 1) / (65535u * uint64_t(x));
  uint64_t sum = 0;
  for (uint64_t j0 = 0; j0 < y; j0 += rows) {
    const uint64_t j1 = j0 + rows < y ? j0 + rows : y;
    sum += uint32_t(s(x, j1) - s(x, j0));  // unsigned wrap-around gives the exact band sum
  }
  return sum;
}

// Integral of the (piecewise-constant) codes over [0, x) x [0, y), real 0 <= x, y <= N: bilinear
// between the exact integer prefix sums at the surrounding texel corners.
double ParallaxView::prefix_integral(uint32_t bin, const uint32_t* table, double x,
                                     double y) const noexcept {
  const uint32_t n = info_.resolution;
  uint32_t i = uint32_t(x), j = uint32_t(y);
  if (i > n) i = n;
  if (j > n) j = n;
  const double fx = i < n ? x - double(i) : 0.0, fy = j < n ? y - double(j) : 0.0;
  const uint32_t i1 = i < n ? i + 1 : n, j1 = j < n ? j + 1 : n;
  if (exact_sums_ && table != nullptr) {
    // N <= 256: every prefix sum is one table entry, exact modulo 2^32 (the differences below
    // are of nested rectangles, so exact too).
    auto at = [&](uint32_t a, uint32_t b) -> uint32_t {
      return (a == 0 || b == 0) ? 0u : table[uint64_t(b - 1) * n + (a - 1)];
    };
    const uint32_t e00 = at(i, j), e10 = at(i1, j), e01 = at(i, j1);
    double value = double(e00);
    if (fx > 0.0) value += fx * double(e10 - e00);
    if (fy > 0.0) value += fy * double(e01 - e00);
    // The texel (i, j) itself from the table (its neighbours in memory), not from the codes.
    if (fx > 0.0 && fy > 0.0) value += fx * fy * double(uint32_t(at(i1, j1) - e10 - e01 + e00));
    return value;
  }
  const uint64_t e00 = prefix_sum_of(table, i, j);
  double value = double(e00);
  if (fx > 0.0) value += fx * double(prefix_sum_of(table, i1, j) - e00);
  if (fy > 0.0) value += fy * double(prefix_sum_of(table, i, j1) - e00);
  if (fx > 0.0 && fy > 0.0) {
    // The texel (i, j) itself: its code times the covered fraction fx * fy.
    value += fx * fy * double(code(bin, uint64_t(j) * n + i));
  }
  return value;
}

double ParallaxView::footprint_code_sum(uint32_t bin, const FootprintPlan& p) const noexcept {
  const double n = double(info_.resolution);
  const uint32_t* table = bin_sat(bin);
  auto in = [&](double x, double y) { return prefix_integral(bin, table, x, y); };
  double f = in(p.rx1, p.ry1) - in(p.x0, p.ry1) - in(p.rx1, p.y0) + in(p.x0, p.y0);
  if (p.qx > 0) f += p.qx * (in(n, p.ry1) - in(n, p.y0));
  if (p.qy > 0) f += p.qy * (in(p.rx1, n) - in(p.x0, n));
  if (p.qx > 0 && p.qy > 0) f += p.qx * p.qy * in(n, n);
  return f;
}

namespace {

// One point (x, y) of a footprint's prefix integrals on the exact-u32 path (N <= 256), reduced
// once per query to the table indices it reads, so that the (up to 4) bins of a lookup only load
// and combine: the same arithmetic as prefix_integral, in the same order (bit for bit the same
// result).
struct ExactCorner {
  int64_t e00 = -1, e10 = -1, e01 = -1, e11 = -1;  // table indices; -1 reads as 0
  double fx = 0.0, fy = 0.0;
};

ExactCorner exact_corner(uint32_t n, double x, double y) noexcept {
  uint32_t i = uint32_t(x), j = uint32_t(y);
  if (i > n) i = n;
  if (j > n) j = n;
  ExactCorner c;
  c.fx = i < n ? x - double(i) : 0.0;
  c.fy = j < n ? y - double(j) : 0.0;
  const uint32_t i1 = i < n ? i + 1 : n, j1 = j < n ? j + 1 : n;
  auto index = [n](uint32_t a, uint32_t b) -> int64_t {
    return (a == 0 || b == 0) ? -1 : int64_t(b - 1) * n + (a - 1);
  };
  c.e00 = index(i, j);
  c.e10 = index(i1, j);
  c.e01 = index(i, j1);
  c.e11 = index(i1, j1);
  return c;
}

double exact_prefix_integral(const uint32_t* table, const ExactCorner& c) noexcept {
  auto at = [table](int64_t t) -> uint32_t { return t < 0 ? 0u : table[t]; };
  const uint32_t e00 = at(c.e00), e10 = at(c.e10), e01 = at(c.e01);
  double value = double(e00);
  if (c.fx > 0.0) value += c.fx * double(e10 - e00);
  if (c.fy > 0.0) value += c.fy * double(e01 - e00);
  if (c.fx > 0.0 && c.fy > 0.0)
    value += c.fx * c.fy * double(uint32_t(at(c.e11) - e10 - e01 + e00));
  return value;
}

// The up to nine points of footprint_code_sum, reduced once per query.
struct ExactFootprint {
  ExactCorner c[9];
  double qx = 0.0, qy = 0.0;
};

ExactFootprint exact_footprint(uint32_t n, const FootprintPlan& p) noexcept {
  const double nn = double(n);
  ExactFootprint f;
  f.qx = p.qx;
  f.qy = p.qy;
  f.c[0] = exact_corner(n, p.rx1, p.ry1);
  f.c[1] = exact_corner(n, p.x0, p.ry1);
  f.c[2] = exact_corner(n, p.rx1, p.y0);
  f.c[3] = exact_corner(n, p.x0, p.y0);
  if (p.qx > 0) {
    f.c[4] = exact_corner(n, nn, p.ry1);
    f.c[5] = exact_corner(n, nn, p.y0);
  }
  if (p.qy > 0) {
    f.c[6] = exact_corner(n, p.rx1, nn);
    f.c[7] = exact_corner(n, p.x0, nn);
  }
  if (p.qx > 0 && p.qy > 0) f.c[8] = exact_corner(n, nn, nn);
  return f;
}

double exact_footprint_sum(const uint32_t* table, const ExactFootprint& f) noexcept {
  auto in = [&](int k) { return exact_prefix_integral(table, f.c[k]); };
  double s = in(0) - in(1) - in(2) + in(3);
  if (f.qx > 0) s += f.qx * (in(4) - in(5));
  if (f.qy > 0) s += f.qy * (in(6) - in(7));
  if (f.qx > 0 && f.qy > 0) s += f.qx * f.qy * in(8);
  return s;
}

}  // namespace

Status ParallaxView::footprint_depth(const Footprint& rect, const double view[3],
                                     ParallaxSample* out) const noexcept {
  if (!is_open() || out == nullptr)
    return Status::error(ErrorCode::InvalidArgument, Check::None, "parallax view is not open");
  if (!has_sat())
    return Status::error(ErrorCode::NotFound, Check::MissingSection,
                         "this asset has no parallax_sat section (footprint queries need it)");

  FootprintPlan plan;
  if (!make_footprint_plan(rect, info_.resolution, &plan))
    return plan_footprint(rect, info_.resolution, &plan);  // the message
  const double area = (rect.x1 - rect.x0) * (rect.y1 - rect.y0);
  if (!(area > 0.0))
    return depth(int64_t(std::floor(rect.x0)), int64_t(std::floor(rect.y0)), view, out);
  double o[3];
  Status s = view_direction(view, o);
  if (!s.ok()) return s;
  const model::DirectionGrid<double> grid{int(info_.dirs), info_.min_cos};
  const model::BinBilinear<double> w = grid.bilinear_fast(model::Vec3d(o[0], o[1], o[2]));
  for (int k = 0; k < 4; ++k)
    if (w.weight[k] > 0.0 && !covers(uint32_t(w.index[k]))) return out_of_plan(w.index[k]);
  // N <= 256: the corners are reduced to table indices once for all bins of the lookup.
  ExactFootprint exact;
  if (exact_sums_) exact = exact_footprint(info_.resolution, plan);
  auto code_sum = [&](uint32_t bin) {
    const uint32_t* table = bin_sat(bin);
    return exact_sums_ && table != nullptr ? exact_footprint_sum(table, exact)
                                           : footprint_code_sum(bin, plan);
  };
  double sum = 0.0;
  if (steps_ == nullptr) {  // raw: one depth scale
    for (int k = 0; k < 4; ++k)
      if (w.weight[k] > 0.0) sum += w.weight[k] * code_sum(uint32_t(w.index[k]));
    sum *= info_.depth_scale;
  } else {
    for (int k = 0; k < 4; ++k)
      if (w.weight[k] > 0.0) {
        if (!ensure_sat(uint32_t(w.index[k])))
          return Status::error(ErrorCode::Unsupported, Check::None,
                               "parallax: cannot allocate the SAT of direction %d", w.index[k]);
        sum += w.weight[k] * code_sum(uint32_t(w.index[k])) * steps_[w.index[k]];
      }
  }
  const double r = -sum / area;
  out->r = r;
  out->offset[0] = r / o[2] * o[0];
  out->offset[1] = r / o[2] * o[1];
  for (int i = 0; i < 3; ++i)
    out->direction[i] = o[i];
  return {};
}

}  // namespace clothbake::reader
