// The SAT normalisation of the paper (Sec. 4.4, Fig. 4): subtract from a table's summed-area
// table the SAT of the table's mean value (a plane through the origin, S_mean(x, y) = m (x+1)
// (y+1) for inclusive corner (x, y)), so that what is left is the deviation from the average,
// then map that deviation to [0, 1] with a stored offset and scale.
//
// clothbake's stored layout compresses per-texel directional vectors instead
// (compress/compressed_set.hpp; docs/compression.md has the measurements that decided it); this
// normalisation serves the paper's whole-SAT layout (sat_pca.hpp), study code that
// sat_layout_study.cpp compares against it.
//
// C++20, pure functions, safe for any finite input (a constant or all-zero table gets scale 1 and
// maps to 0).
#pragma once

#include <cstddef>

namespace clothbake::compress {

enum class SatNormalisation {
  None,       // the SAT itself
  Plane,      // S - S_mean
  PlaneUnit,  // (S - S_mean - offset) / scale in [0, 1]: the paper's
};

const char* sat_normalisation_name(SatNormalisation mode);  // "none", "plane", "plane+unit"

struct SatTransform {
  double mean = 0.0;    // m, the table's mean texel value
  double offset = 0.0;  // min of the deviation (PlaneUnit), else 0
  double scale = 1.0;   // max - min of the deviation (PlaneUnit; 1 when that is 0), else 1
  bool plane = false;   // S_mean subtracted

  // The SAT value at inclusive corner (x, y) from a stored (normalised) value.
  double restore(double stored, int x, int y) const {
    return scale * stored + offset + (plane ? mean * double(x + 1) * double(y + 1) : 0.0);
  }
};

// Inclusive SAT (double) of an n x n table (row-major) into sat (n * n values).
void summed_area_table(const float* table, int n, double* sat);

// Normalises the inclusive SAT `sat` (n x n) into `out` (n * n floats) and returns the transform.
SatTransform normalise_sat(const double* sat, int n, SatNormalisation mode, float* out);

}  // namespace clothbake::compress
