#include "fabric/fabric_json.hpp"

namespace clothbake {

nlohmann::json bake_settings_json(const BakeSettings& b) {
  return {{"resolution", b.resolution},
          {"parallax_dirs", b.parallax_dirs},
          {"parallax_min_cos", b.parallax_min_cos},
          {"parallax_max_error", b.parallax_max_error},
          {"visibility_dirs", b.visibility_dirs},
          {"radiance_dirs", b.radiance_dirs},
          {"clusters", b.clusters},
          {"clusters_by_yarn", b.clusters_by_yarn},
          {"visibility_rank", b.visibility_rank},
          {"compress", b.compress},
          {"compress_clusters", b.compress_clusters},
          {"compress_rank", b.compress_rank},
          {"seed", b.seed}};
}

}  // namespace clothbake
