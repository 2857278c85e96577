// Writes a fitted sheen table as the C++17 header that model/sheen.hpp reads
// (model/sheen_table.hpp for the published convention, model/sheen_table_converged.hpp for the
// converged one), and writes files atomically.
#pragma once

#include <string>

#include "sheen/sheen_fit.hpp"

namespace clothbake::sheen {

// The header text: generator settings (the convention's simulation rules included) and fit
// statistics in comments and constants, in namespace clothbake::model::sheen_table (published) or
// sheen_table_converged (converged), then
// kTable[roughness index][cos index] = {a, b, R} as float literals that round-trip exactly.
// Contains no timestamps or paths: the same fit gives the same bytes.
std::string format_sheen_table_header(const SheenTableFit& fit);

}  // namespace clothbake::sheen
