// Which stages run and in what order: the picked stages, every stage that produces one of their
// inputs (transitively), and the `always` stages, topologically sorted (ties broken by name, so
// the order is deterministic).
#pragma once

#include <set>
#include <string>
#include <vector>

#include "bake/pipeline/stage.hpp"

namespace clothbake::pipeline {

// `picked` empty means every stage of `stages` whose outputs are not already `seeded`.
// Throws Error(Usage) for an unknown stage name (listing the known ones); Error(Internal) when
// two stages produce the same artifact, an input has no producer, or the dependencies form a
// cycle (naming the stages on it).
std::vector<const Stage*> plan_stages(const std::vector<Stage>& stages,
                                      const std::vector<std::string>& picked,
                                      const std::set<std::string>& seeded);

}  // namespace clothbake::pipeline
