// Deterministic K-means: k-means++ seeding, Lloyd iterations, empty-cluster repair (kmeans.hpp).
#include "cluster/kmeans.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "cluster/nearest_centre.hpp"
#include "common/error.hpp"
#include "model/splitmix64.hpp"

namespace clothbake::cluster {

namespace {

struct Blocks {
  std::size_t count = 0;  // number of points
  std::size_t blocks = 0;
  std::size_t begin(std::size_t b) const { return b * kBlockPoints; }
  std::size_t end(std::size_t b) const { return std::min(count, (b + 1) * kBlockPoints); }
};

// Runs fn(block) for every block, in parallel; fn must write only block-owned outputs.
template <class Fn>
void for_each_block(const Blocks& blocks, Fn&& fn) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.blocks, 1),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t b = range.begin(); b != range.end(); ++b)
                        fn(b);
                    });
}

void validate(const PointSet& points, const KMeansOptions& options, const Blocks& blocks) {
  if (points.count == 0) throw_input_error("k-means: no points to cluster");
  if (points.dim == 0) throw_input_error("k-means: points have dimension 0");
  if (points.data == nullptr) throw_input_error("k-means: null point data");
  if (options.clusters < 1)
    throw_input_error("k-means: clusters = " + std::to_string(options.clusters) +
                      " must be at least 1");
  if (options.max_iterations < 1)
    throw_input_error("k-means: max_iterations = " + std::to_string(options.max_iterations) +
                      " must be at least 1");
  // First non-finite coordinate (lowest index), found per block in parallel.
  std::vector<std::size_t> first_bad(blocks.blocks, std::numeric_limits<std::size_t>::max());
  for_each_block(blocks, [&](std::size_t b) {
    const float* p = points.data;
    for (std::size_t k = blocks.begin(b) * points.dim; k < blocks.end(b) * points.dim; ++k)
      if (!std::isfinite(p[k])) {
        first_bad[b] = k;
        return;
      }
  });
  for (std::size_t k : first_bad)
    if (k != std::numeric_limits<std::size_t>::max())
      throw_input_error("k-means: point " + std::to_string(k / points.dim) + " coordinate " +
                        std::to_string(k % points.dim) + " is not finite (" +
                        std::to_string(points.data[k]) + ")");
}

// k-means++ seeding; returns the number of centres chosen (fewer than requested only when every
// point already coincides with a chosen centre).
int seed_centres(const PointSet& points, const Blocks& blocks, int clusters, uint64_t seed,
                 std::vector<double>& centres) {
  const std::size_t n = points.count, dim = points.dim;
  model::SplitMix64 rng(seed);
  centres.assign(std::size_t(clusters) * dim, 0.0);
  auto set_centre = [&](int c, std::size_t i) {
    for (std::size_t j = 0; j < dim; ++j)
      centres[std::size_t(c) * dim + j] = points.point(i)[j];
  };
  set_centre(0, std::size_t(rng.below(n)));
  std::vector<double> nearest2(n);
  for_each_block(blocks, [&](std::size_t b) {
    for (std::size_t i = blocks.begin(b); i < blocks.end(b); ++i)
      nearest2[i] = squared_distance(points.point(i), centres.data(), dim);
  });
  std::vector<double> block_sum(blocks.blocks);
  int chosen = 1;
  for (; chosen < clusters; ++chosen) {
    for_each_block(blocks, [&](std::size_t b) {
      double s = 0;
      for (std::size_t i = blocks.begin(b); i < blocks.end(b); ++i)
        s += nearest2[i];
      block_sum[b] = s;
    });
    double total = 0;
    for (double s : block_sum)
      total += s;
    if (!(total > 0)) break;  // every point coincides with a centre: no new distinct centre
    // D^2 sampling: the first point whose running sum exceeds target.
    const double target = rng.uniform() * total;
    std::size_t pick = n;
    double running = 0;
    for (std::size_t b = 0; b < blocks.blocks && pick == n; ++b) {
      if (running + block_sum[b] <= target && b + 1 < blocks.blocks) {
        running += block_sum[b];
        continue;
      }
      for (std::size_t i = blocks.begin(b); i < blocks.end(b); ++i) {
        running += nearest2[i];
        if (running > target && nearest2[i] > 0) {
          pick = i;
          break;
        }
      }
    }
    if (pick == n) {  // rounding at the very end of the sum: the last point with weight
      for (std::size_t i = n; i-- > 0;)
        if (nearest2[i] > 0) {
          pick = i;
          break;
        }
    }
    set_centre(chosen, pick);
    const double* c = &centres[std::size_t(chosen) * dim];
    for_each_block(blocks, [&](std::size_t b) {
      for (std::size_t i = blocks.begin(b); i < blocks.end(b); ++i)
        nearest2[i] = std::min(nearest2[i], squared_distance(points.point(i), c, dim));
    });
  }
  centres.resize(std::size_t(chosen) * dim);
  return chosen;
}

// Moves into each empty cluster the point farthest from its centre among clusters of size >= 2.
int repair_empty_clusters(const Blocks& blocks, int clusters, std::vector<int32_t>& labels,
                          std::vector<double>& distance2, std::vector<uint64_t>& sizes) {
  int repairs = 0;
  std::vector<std::size_t> block_best(blocks.blocks);
  for (int empty = 0; empty < clusters; ++empty) {
    if (sizes[std::size_t(empty)] != 0) continue;
    for_each_block(blocks, [&](std::size_t b) {
      std::size_t best = blocks.count;
      double best_d = 0;
      for (std::size_t i = blocks.begin(b); i < blocks.end(b); ++i)
        if (sizes[std::size_t(labels[i])] >= 2 && distance2[i] > best_d) {
          best_d = distance2[i];
          best = i;
        }
      block_best[b] = best;
    });
    std::size_t best = blocks.count;
    for (std::size_t b = 0; b < blocks.blocks; ++b) {
      const std::size_t i = block_best[b];
      if (i != blocks.count && (best == blocks.count || distance2[i] > distance2[best])) best = i;
    }
    if (best == blocks.count) continue;  // every point sits on its centre: nothing to move
    --sizes[std::size_t(labels[best])];
    labels[best] = empty;
    distance2[best] = 0;
    sizes[std::size_t(empty)] = 1;
    ++repairs;
  }
  return repairs;
}

// Centres = means of their points (fixed-order block reduction). Empty clusters keep their centre.
void update_centres(const PointSet& points, const Blocks& blocks, int clusters,
                    const std::vector<int32_t>& labels, std::vector<double>& centres) {
  const std::size_t dim = points.dim, k = std::size_t(clusters);
  std::vector<double> partial(blocks.blocks * k * dim, 0.0);
  std::vector<uint64_t> counts(blocks.blocks * k, 0);
  for_each_block(blocks, [&](std::size_t b) {
    double* sum = &partial[b * k * dim];
    uint64_t* count = &counts[b * k];
    for (std::size_t i = blocks.begin(b); i < blocks.end(b); ++i) {
      const std::size_t c = std::size_t(labels[i]);
      const float* p = points.point(i);
      double* s = sum + c * dim;
      for (std::size_t j = 0; j < dim; ++j)
        s[j] += p[j];
      ++count[c];
    }
  });
  std::vector<double> total(k * dim, 0.0);
  std::vector<uint64_t> size(k, 0);
  for (std::size_t b = 0; b < blocks.blocks; ++b) {
    for (std::size_t t = 0; t < k * dim; ++t)
      total[t] += partial[b * k * dim + t];
    for (std::size_t c = 0; c < k; ++c)
      size[c] += counts[b * k + c];
  }
  for (std::size_t c = 0; c < k; ++c) {
    if (size[c] == 0) continue;
    for (std::size_t j = 0; j < dim; ++j)
      centres[c * dim + j] = total[c * dim + j] / double(size[c]);
  }
}

}  // namespace

KMeansResult kmeans(const PointSet& points, const KMeansOptions& options) {
  Blocks blocks{points.count, (points.count + kBlockPoints - 1) / kBlockPoints};
  validate(points, options, blocks);
  const std::size_t n = points.count, dim = points.dim;

  KMeansResult result;
  result.dim = dim;
  std::vector<double> centres;
  int k = 0;
  if (options.initial_centres != nullptr) {
    k = options.clusters;
    centres.assign(options.initial_centres, options.initial_centres + std::size_t(k) * dim);
    for (std::size_t t = 0; t < centres.size(); ++t)
      if (!std::isfinite(centres[t]))
        throw_input_error("k-means: initial centre " + std::to_string(t / dim) + " coordinate " +
                          std::to_string(t % dim) + " is not finite");
  } else {
    const int requested = int(std::min<std::size_t>(std::size_t(options.clusters), n));
    k = seed_centres(points, blocks, requested, options.seed, centres);
  }

  std::vector<int32_t> labels(n, -1), previous(n, -1);
  std::vector<double> distance2(n, 0.0);
  std::vector<uint64_t> sizes(std::size_t(k), 0);
  std::vector<uint64_t> block_changes(blocks.blocks);
  for (int iteration = 1; iteration <= options.max_iterations; ++iteration) {
    auto search = make_centre_search(centres.data(), k, dim);
    for_each_block(blocks, [&](std::size_t b) {
      search->assign(points, blocks.begin(b), blocks.end(b), labels.data(), distance2.data());
      uint64_t changes = 0;
      for (std::size_t i = blocks.begin(b); i < blocks.end(b); ++i)
        changes += labels[i] != previous[i];
      block_changes[b] = changes;
    });
    uint64_t changes = 0;
    for (uint64_t c : block_changes)
      changes += c;
    std::fill(sizes.begin(), sizes.end(), 0);
    for (int32_t label : labels)
      ++sizes[std::size_t(label)];
    const int repairs = repair_empty_clusters(blocks, k, labels, distance2, sizes);
    result.empty_repairs += repairs;
    result.iterations = iteration;
    if (changes == 0 && repairs == 0) {  // centres are already the means of these labels
      result.converged = true;
      break;
    }
    update_centres(points, blocks, k, labels, centres);
    previous = labels;
  }

  // Final statistics against the final centres; empty clusters are dropped and the rest renumbered
  // in order.
  std::fill(sizes.begin(), sizes.end(), 0);
  for (int32_t label : labels)
    ++sizes[std::size_t(label)];
  std::vector<int32_t> renumber(std::size_t(k), -1);
  int kept = 0;
  for (int c = 0; c < k; ++c)
    if (sizes[std::size_t(c)] > 0) renumber[std::size_t(c)] = kept++;
  result.clusters = kept;
  result.centres.resize(std::size_t(kept) * dim);
  result.sizes.resize(std::size_t(kept));
  for (int c = 0; c < k; ++c) {
    const int32_t r = renumber[std::size_t(c)];
    if (r < 0) continue;
    std::copy_n(&centres[std::size_t(c) * dim], dim, &result.centres[std::size_t(r) * dim]);
    result.sizes[std::size_t(r)] = sizes[std::size_t(c)];
  }
  result.labels.resize(n);
  std::vector<double> partial(blocks.blocks * std::size_t(kept), 0.0);
  for_each_block(blocks, [&](std::size_t b) {
    for (std::size_t i = blocks.begin(b); i < blocks.end(b); ++i) {
      const int32_t r = renumber[std::size_t(labels[i])];
      result.labels[i] = r;
      partial[b * std::size_t(kept) + std::size_t(r)] +=
          squared_distance(points.point(i), &result.centres[std::size_t(r) * dim], dim);
    }
  });
  result.inertia.assign(std::size_t(kept), 0.0);
  for (std::size_t b = 0; b < blocks.blocks; ++b)
    for (int c = 0; c < kept; ++c)
      result.inertia[std::size_t(c)] += partial[b * std::size_t(kept) + std::size_t(c)];
  for (double v : result.inertia)
    result.total_inertia += v;
  return result;
}

}  // namespace clothbake::cluster
