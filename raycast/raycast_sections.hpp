// Asset sections of the ray-casting stages (layouts: formats/reader/parallax_sections.hpp and
// formats/reader/visibility_sections.hpp; docs/raycast.md).
#pragma once

#include <vector>

#include "formats/writer/asset_writer.hpp"
#include "model/asg.hpp"
#include "raycast/parallax.hpp"
#include "raycast/visibility.hpp"

namespace clothbake::raycast {

// ParallaxTable instances 0 (info) and 1 (codes) and ParallaxSat instance 0. Consumes the table
// (its codes are moved into the section and the SAT is computed straight into its payload), so
// that the peak memory is the codes plus the SAT, 6 bytes per texel and direction.
std::vector<formats::Section> parallax_sections(ParallaxTable&& table);

// VisibilityAsg instances 0 (info) and 1 (records) and, with `fit_error_section`, AsgFitError
// instance 0 (information only: the bake writes it with --keep-raw; the info record's mean and
// maximum fit error are filled either way).
std::vector<formats::Section> visibility_sections(const VisibilityAsgs& asgs,
                                                  const VisibilitySettings& settings, int dirs,
                                                  bool fit_error_section = true);

// The stored lobes decoded (what a renderer sees), texel order: for the visibility clustering.
std::vector<model::AsgParams<float>> decoded_lobes(const VisibilityAsgs& asgs);

}  // namespace clothbake::raycast
