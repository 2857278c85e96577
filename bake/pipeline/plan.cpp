#include "bake/pipeline/plan.hpp"

#include <algorithm>
#include <map>

#include "common/error.hpp"

namespace clothbake::pipeline {
namespace {

bool starts_with(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names)
    out += (out.empty() ? "" : ", ") + n;
  return out;
}

}  // namespace

std::vector<const Stage*> plan_stages(const std::vector<Stage>& stages,
                                      const std::vector<std::string>& picked,
                                      const std::set<std::string>& seeded) {
  std::map<std::string, const Stage*> by_name;
  std::map<std::string, const Stage*> producer;
  for (const Stage& s : stages) {
    if (!by_name.emplace(s.name, &s).second)
      throw_internal_error("two pipeline stages are named '" + s.name + "'");
    for (const auto& out : s.outputs) {
      auto [it, inserted] = producer.emplace(out, &s);
      if (!inserted)
        throw_internal_error("artifact '" + out + "' is produced by both stage '" +
                             it->second->name + "' and stage '" + s.name + "'");
    }
  }

  // Selection.
  std::set<std::string> selected;
  if (picked.empty()) {
    for (const Stage& s : stages) {
      const bool all_seeded =
          !s.outputs.empty() && std::all_of(s.outputs.begin(), s.outputs.end(),
                                            [&](const std::string& o) { return seeded.count(o); });
      if (!all_seeded) selected.insert(s.name);
    }
  } else {
    for (const auto& name : picked) {
      if (!by_name.count(name)) {
        std::vector<std::string> known;
        for (const auto& [n, s] : by_name)
          known.push_back(n);
        throw Error(ExitCode::Usage,
                    "unknown stage '" + name + "' in --stages; known stages: " + join(known));
      }
      selected.insert(name);
    }
    for (const Stage& s : stages)
      if (s.always) selected.insert(s.name);
  }
  // Pull in producers of inputs, transitively.
  std::vector<std::string> work(selected.begin(), selected.end());
  while (!work.empty()) {
    const Stage* s = by_name.at(work.back());
    work.pop_back();
    for (const auto& in : s->inputs) {
      if (seeded.count(in)) continue;
      auto it = producer.find(in);
      if (it == producer.end())
        throw_internal_error("stage '" + s->name + "' needs artifact '" + in +
                             "' but no stage produces it");
      if (selected.insert(it->second->name).second) work.push_back(it->second->name);
    }
  }

  // Edges: producer -> consumer, for inputs and collected prefixes (among selected stages).
  std::map<std::string, std::set<std::string>> successors;
  std::map<std::string, int> indegree;
  for (const auto& name : selected)
    indegree[name] = 0;
  auto add_edge = [&](const std::string& from, const std::string& to) {
    if (successors[from].insert(to).second) ++indegree[to];
  };
  for (const auto& name : selected) {
    const Stage* s = by_name.at(name);
    for (const auto& in : s->inputs)
      if (!seeded.count(in)) add_edge(producer.at(in)->name, name);
    for (const auto& prefix : s->collects)
      for (const auto& other : selected) {
        if (other == name) continue;
        for (const auto& out : by_name.at(other)->outputs)
          if (starts_with(out, prefix)) add_edge(other, name);
      }
  }

  // Kahn's algorithm, smallest name first among the ready stages.
  std::set<std::string> ready;
  for (const auto& [name, d] : indegree)
    if (d == 0) ready.insert(name);
  std::vector<const Stage*> order;
  while (!ready.empty()) {
    const std::string name = *ready.begin();
    ready.erase(ready.begin());
    order.push_back(by_name.at(name));
    for (const auto& next : successors[name])
      if (--indegree[next] == 0) ready.insert(next);
  }
  if (order.size() != selected.size()) {
    std::vector<std::string> stuck;
    for (const auto& [name, d] : indegree)
      if (d > 0) stuck.push_back(name);
    throw_internal_error("pipeline stages depend on each other in a cycle: " + join(stuck));
  }
  return order;
}

}  // namespace clothbake::pipeline
