// Visibility cluster sections and metadata (cluster_sections.hpp).
#include "cluster/cluster_sections.hpp"

#include "common/error.hpp"

namespace clothbake::cluster {

std::vector<formats::Section> cluster_sections(const VisibilityClusters& c) {
  const uint32_t n = uint32_t(c.resolution), d = uint32_t(c.visibility_dirs),
                 k = uint32_t(c.clusters);
  if (c.labels.size() != std::size_t(n) * n || c.mean_visibility.size() != std::size_t(k) * d * d ||
      k == 0)
    throw_internal_error("visibility clusters: inconsistent sizes");
  std::vector<formats::Section> out;
  out.push_back(formats::make_array_section<uint8_t>(reader::SectionType::ClusterLabels, 0,
                                                     c.labels, {n, n}));
  out.push_back(formats::make_array_section<float>(reader::SectionType::ClusterMeanVisibility, 0,
                                                   c.mean_visibility, {k, d, d}));
  return out;
}

std::vector<formats::Section> visibility_basis_sections(const VisibilityBasis& b) {
  const uint32_t n = uint32_t(b.resolution), d = uint32_t(b.dirs), k = uint32_t(b.clusters),
                 m = uint32_t(b.rank);
  if (k == 0 || b.components.size() != std::size_t(k) * (m + 1) * d * d ||
      b.coefficients.size() != std::size_t(n) * n * m)
    throw_internal_error("visibility basis: inconsistent sizes");
  std::vector<formats::Section> out;
  out.push_back(formats::make_array_section<float>(reader::SectionType::ClusterVisibilityBasis, 0,
                                                   b.components, {k, m + 1, d, d}));
  if (m > 0)
    out.push_back(formats::make_array_section<float>(reader::SectionType::ClusterVisibilityBasis, 1,
                                                     b.coefficients, {n, n, m}));
  return out;
}

nlohmann::json cluster_metadata(const VisibilityClusters& c,
                                const VisibilityClusterOptions& options) {
  nlohmann::json per_cluster = nlohmann::json::array();
  for (const ClusterStats& s : c.stats)
    per_cluster.push_back({{"texels", s.texels},
                           {"inertia", s.inertia},
                           {"visibility_variance", s.variance},
                           {"residual_variance", s.residual_variance},
                           {"explained_fraction", s.explained_fraction}});
  return {{"requested_clusters", options.clusters},
          {"clusters", c.clusters},
          {"seed", options.seed},
          {"visibility_dirs", c.visibility_dirs},
          {"samples_per_bin_side", c.samples_per_bin_side},
          {"embedding_weights",
           {{"axis", options.weights.axis},
            {"bandwidth", options.weights.bandwidth},
            {"amplitude", options.weights.amplitude}}},
          {"kmeans",
           {{"iterations", c.kmeans.iterations},
            {"converged", c.kmeans.converged},
            {"empty_repairs", c.kmeans.empty_repairs},
            {"total_inertia", c.kmeans.total_inertia}}},
          {"visibility_variance", c.variance},
          {"residual_variance", c.residual_variance},
          {"explained_fraction", c.explained_fraction},
          {"per_cluster", per_cluster}};
}

}  // namespace clothbake::cluster
