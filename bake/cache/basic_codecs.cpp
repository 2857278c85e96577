// Codecs of the artifact types below bake/cache (codec.hpp). The static_asserts on struct sizes
// fail the build when a field is added to an encoded struct, so that the codec (and therefore the
// cache key, which hashes the encoding) cannot silently miss it.
#include <nlohmann/json.hpp>

#include "bake/cache/codec.hpp"
#include "fabric/fabric.hpp"
#include "formats/validate/metadata_limits.hpp"
#include "formats/writer/asset_writer.hpp"

namespace clothbake::cache {
namespace {

static_assert(sizeof(FabricMaps) == 8 + 6 * sizeof(std::vector<float>),
              "FabricMaps changed: update encode_fabric in bake/cache/basic_codecs.cpp");
static_assert(sizeof(YarnMaterial) == sizeof(std::string) + 2 * 8 + 4 * sizeof(Rgb),
              "YarnMaterial changed: update encode_fabric in bake/cache/basic_codecs.cpp");
static_assert(sizeof(SheenParams) == sizeof(Rgb) + 8,
              "SheenParams changed: update encode_fabric in bake/cache/basic_codecs.cpp");
static_assert(sizeof(BakeSettings) == 64,
              "BakeSettings changed: update encode_fabric in bake/cache/basic_codecs.cpp");
static_assert(sizeof(InputFile) == 3 * sizeof(std::string),
              "InputFile changed: update encode_fabric in bake/cache/basic_codecs.cpp");
static_assert(sizeof(Fabric) == sizeof(std::string) + sizeof(FabricMaps) +
                                    sizeof(std::vector<YarnMaterial>) + sizeof(SheenParams) +
                                    sizeof(BakeSettings) + sizeof(std::vector<InputFile>) + 8,
              "Fabric changed: update encode_fabric in bake/cache/basic_codecs.cpp");
static_assert(sizeof(formats::Section) == 8 + 8 + 2 * sizeof(std::vector<uint32_t>) +
                                              sizeof(std::span<const std::byte>) +
                                              sizeof(std::shared_ptr<const void>),
              "formats::Section changed: update the section codec in bake/cache/basic_codecs.cpp");

void encode_fabric(const Fabric& f, ByteWriter& w) {
  w.str(f.name);
  w.pod(int32_t(f.maps.resolution));
  w.vec(f.maps.height);
  w.vec(f.maps.tangent);
  w.vec(f.maps.normal);
  w.vec(f.maps.gap);
  w.vec(f.maps.yarn_id);
  w.vec(f.maps.albedo);
  w.pod(uint64_t(f.yarns.size()));
  for (const auto& y : f.yarns) {
    w.str(y.name);
    w.pod(y.roughness);
    w.pod(y.optical_thickness);
    w.pod(y.specular_albedo);
    w.pod(y.diffuse_reflectance);
    w.pod(y.diffuse_transmittance);
    w.pod(y.color);
  }
  w.pod(f.sheen.color);
  w.pod(f.sheen.roughness);
  const BakeSettings& b = f.bake;
  w.pod(int32_t(b.resolution));
  w.pod(int32_t(b.parallax_dirs));
  w.pod(b.parallax_min_cos);
  w.pod(b.parallax_max_error);
  w.pod(int32_t(b.visibility_dirs));
  w.pod(int32_t(b.radiance_dirs));
  w.pod(int32_t(b.clusters));
  w.pod(uint8_t(b.clusters_by_yarn));
  w.pod(int32_t(b.visibility_rank));
  w.pod(uint8_t(b.compress));
  w.pod(int32_t(b.compress_clusters));
  w.pod(int32_t(b.compress_rank));
  w.pod(b.seed);
  w.pod(uint64_t(f.inputs.size()));
  for (const auto& i : f.inputs) {
    w.str(i.role);
    w.str(i.path);
    w.str(i.xxh64);
  }
  w.pod(f.tile_size_mm);
}

Fabric decode_fabric(ByteReader& r) {
  Fabric f;
  f.name = r.str();
  f.maps.resolution = r.pod<int32_t>();
  f.maps.height = r.vec<float>();
  f.maps.tangent = r.vec<Vec3f>();
  f.maps.normal = r.vec<Vec3f>();
  f.maps.gap = r.vec<float>();
  f.maps.yarn_id = r.vec<uint16_t>();
  f.maps.albedo = r.vec<Vec3f>();
  const uint64_t yarns = r.pod<uint64_t>();
  for (uint64_t k = 0; k < yarns; ++k) {
    YarnMaterial y;
    y.name = r.str();
    y.roughness = r.pod<double>();
    y.optical_thickness = r.pod<double>();
    y.specular_albedo = r.pod<Rgb>();
    y.diffuse_reflectance = r.pod<Rgb>();
    y.diffuse_transmittance = r.pod<Rgb>();
    y.color = r.pod<Rgb>();
    f.yarns.push_back(std::move(y));
  }
  f.sheen.color = r.pod<Rgb>();
  f.sheen.roughness = r.pod<double>();
  BakeSettings& b = f.bake;
  b.resolution = r.pod<int32_t>();
  b.parallax_dirs = r.pod<int32_t>();
  b.parallax_min_cos = r.pod<double>();
  b.parallax_max_error = r.pod<double>();
  b.visibility_dirs = r.pod<int32_t>();
  b.radiance_dirs = r.pod<int32_t>();
  b.clusters = r.pod<int32_t>();
  b.clusters_by_yarn = r.pod<uint8_t>() != 0;
  b.visibility_rank = r.pod<int32_t>();
  b.compress = r.pod<uint8_t>() != 0;
  b.compress_clusters = r.pod<int32_t>();
  b.compress_rank = r.pod<int32_t>();
  b.seed = r.pod<uint64_t>();
  const uint64_t inputs = r.pod<uint64_t>();
  for (uint64_t k = 0; k < inputs; ++k) {
    InputFile i;
    i.role = r.str();
    i.path = r.str();
    i.xxh64 = r.str();
    f.inputs.push_back(std::move(i));
  }
  f.tile_size_mm = r.pod<double>();
  return f;
}

// Each payload starts at a multiple of 64 bytes of the encoding (the entry puts encodings at
// multiples of 64 too), so that a mapped entry lends it in place with the alignment of any element.
void encode_sections(const std::vector<formats::Section>& sections, ByteWriter& w) {
  w.pod(uint64_t(sections.size()));
  for (const auto& s : sections) {
    w.pod(uint32_t(s.type));
    w.pod(s.instance);
    w.pod(s.version);
    w.pod(uint16_t(s.element));
    w.vec(s.dims);
    w.pad_before(8 + 8, 64);  // the pad's own length and the payload's length follow
    w.span(s.bytes());
  }
}

// Payloads of at least this size are borrowed from a mapped entry rather than copied.
constexpr std::size_t kBorrowBytes = 4096;

std::vector<formats::Section> decode_sections(ByteReader& r) {
  std::vector<formats::Section> out;
  const uint64_t n = r.pod<uint64_t>();
  for (uint64_t k = 0; k < n; ++k) {
    formats::Section s;
    s.type = formats::SectionType(r.pod<uint32_t>());
    s.instance = r.pod<uint32_t>();
    s.version = r.pod<uint16_t>();
    s.element = formats::ElementType(r.pod<uint16_t>());
    s.dims = r.vec<uint32_t>();
    r.skip_pad();
    const std::span<const std::byte> bytes = r.borrow();
    if (r.owner() && bytes.size() >= kBorrowBytes) {
      s.mapped = bytes;
      s.mapped_owner = r.owner();
    } else {
      s.payload.assign(bytes.begin(), bytes.end());
    }
    // Checked as the writer would check it, but as bad input (a corrupt entry), not a bug.
    if (const std::string problem = formats::section_problem(s); !problem.empty())
      throw_input_error("section " + formats::section_label(s.type, s.instance) + ": " + problem);
    out.push_back(std::move(s));
  }
  return out;
}

// Refuses (Error(Input)) CBOR nested deeper than an asset's metadata may be
// (reader::kMaxMetadataDepth arrays and maps: stage parameters end up there), before the recursive
// decoder sees it: a SAX pass that stops at the first level too deep.
void check_cbor_nesting(const std::vector<uint8_t>& cbor) {
  struct DepthLimit : nlohmann::json_sax<nlohmann::json> {
    std::size_t depth = 0;
    bool too_deep = false;
    bool open() {
      too_deep = ++depth > reader::kMaxMetadataDepth;
      return !too_deep;
    }
    bool null() override { return true; }
    bool boolean(bool) override { return true; }
    bool number_integer(number_integer_t) override { return true; }
    bool number_unsigned(number_unsigned_t) override { return true; }
    bool number_float(number_float_t, const string_t&) override { return true; }
    bool string(string_t&) override { return true; }
    bool binary(binary_t&) override { return true; }
    bool start_object(std::size_t) override { return open(); }
    bool key(string_t&) override { return true; }
    bool end_object() override { return --depth, true; }
    bool start_array(std::size_t) override { return open(); }
    bool end_array() override { return --depth, true; }
    bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
      return false;
    }
  } sax;
  nlohmann::json::sax_parse(cbor, &sax, nlohmann::json::input_format_t::cbor);
  if (sax.too_deep)
    throw_input_error("JSON nested deeper than " + std::to_string(reader::kMaxMetadataDepth) +
                      " levels");
}

}  // namespace

void add_basic_codecs(Codecs& codecs) {
  codecs.add<std::string>(
      "string", [](const std::string& s, ByteWriter& w) { w.str(s); },
      [](ByteReader& r) { return r.str(); });
  codecs.add<std::vector<std::string>>(
      "strings",
      [](const std::vector<std::string>& v, ByteWriter& w) {
        w.pod(uint64_t(v.size()));
        for (const auto& s : v)
          w.str(s);
      },
      [](ByteReader& r) {
        std::vector<std::string> v(r.count(sizeof(uint64_t)));  // each at least its length
        for (auto& s : v)
          s = r.str();
        return v;
      });
  // CBOR keeps the JSON types (integer or double, exactly) and the sorted key order.
  codecs.add<nlohmann::json>(
      "json/cbor",
      [](const nlohmann::json& j, ByteWriter& w) { w.vec(nlohmann::json::to_cbor(j)); },
      [](ByteReader& r) {
        const std::vector<uint8_t> cbor = r.vec<uint8_t>();
        check_cbor_nesting(cbor);  // nlohmann's CBOR reader recurses once per level
        return nlohmann::json::from_cbor(cbor);
      });
  codecs.add<std::vector<formats::Section>>("sections/2", encode_sections, decode_sections);
  codecs.add<Fabric>("fabric/1", encode_fabric, decode_fabric);
}

}  // namespace clothbake::cache
