// PROVISIONAL sheen LTC table: a plain cosine lobe with zero albedo, so that the model library can
// integrate the sheen API before the fitted table lands. `clothbake fit-sheen` replaces this file.
// Layout (docs/sheen.md): kTable[roughness index][cos index] = {a, b, R}, nodes at i / (count - 1).
#pragma once

namespace clothbake::model::sheen_table {

inline constexpr int kCosCount = 2;
inline constexpr int kRoughnessCount = 2;
inline constexpr float kTable[kRoughnessCount][kCosCount][3] = {
    {{1.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}},
    {{1.0f, 0.0f, 0.0f}, {1.0f, 0.0f, 0.0f}},
};

}  // namespace clothbake::model::sheen_table
