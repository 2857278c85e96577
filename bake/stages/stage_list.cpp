#include "bake/stages/stages.hpp"

namespace clothbake::stages {

std::vector<pipeline::Stage> bake_stages() {
  // Run order of a full bake. Keep it equal to the order the driver derives from the stages'
  // inputs and outputs (checked by tests/bake/stages/test_stage_list.cpp).
  return {load_fabric_stage(), fabric_records_stage(), feature_maps_stage(),
          parallax_stage(),    visibility_stage(),     cluster_stage(),
          tables_stage(),      compress_stage(),       write_stage()};
}

}  // namespace clothbake::stages
