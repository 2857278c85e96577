// Opening the sections behind a view (internal to the reader library; not installed): the steps
// that the parallax, visibility and cluster views share, so that they check presence, payload
// version and element type the same way and with the same error classes.
//
// C++17, standard library only, noexcept, no allocation.
#pragma once

#include "formats/reader/asset.hpp"

namespace clothbake::reader::detail {

// A section by key.
struct SectionKey {
  SectionType type;
  uint32_t instance;
};

// Finds the two sections a view needs and views them as A and B. Errors: NotFound
// (CBK-E019, Check::MissingSection) with `missing` when either is absent; Unsupported (CBK-E015,
// Check::SectionLayout) with `wrong_version` when either has a payload version other than
// `version` (the one the caller knows); the view_of errors (WrongType, ...) otherwise. The caller
// checks ranks, dimensions and values.
template <class A, class B>
Status view_required_pair(const Asset& asset, SectionKey a, SectionKey b, const char* missing,
                          const char* wrong_version, ArrayView<A>* view_a, ArrayView<B>* view_b,
                          uint16_t version = 1) noexcept {
  SectionInfo info_a, info_b;
  Status s = asset.find(a.type, a.instance, &info_a);
  if (s.ok()) s = asset.find(b.type, b.instance, &info_b);
  if (s.code() == ErrorCode::NotFound)
    return Status::error(ErrorCode::NotFound, Check::MissingSection, "%s", missing);
  if (!s.ok()) return s;
  if (info_a.version != version || info_b.version != version)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout, "%s", wrong_version);
  s = asset.view_of(info_a, view_a);
  if (s.ok()) s = asset.view_of(info_b, view_b);
  return s;
}

// Views an optional section as T. An absent section is not an error: *present is false and the
// Status ok. Unsupported (CBK-E015) with `wrong_version` for a payload version other than
// `version`; the view_of errors otherwise.
template <class T>
Status view_optional(const Asset& asset, SectionKey key, const char* wrong_version,
                     ArrayView<T>* view, bool* present, uint16_t version = 1) noexcept {
  *present = false;
  SectionInfo info;
  Status s = asset.find(key.type, key.instance, &info);
  if (s.code() == ErrorCode::NotFound) return {};
  if (!s.ok()) return s;
  if (info.version != version)
    return Status::error(ErrorCode::Unsupported, Check::SectionLayout, "%s", wrong_version);
  s = asset.view_of(info, view);
  *present = s.ok();
  return s;
}

}  // namespace clothbake::reader::detail
