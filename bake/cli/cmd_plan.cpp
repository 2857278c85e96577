// clothbake plan: what each fabric of a scene needs (docs/scene-format.md, "Bake plans").
//
//   clothbake plan SCENE.toml [--json]
//
// Analyses the scene as the renderer sees it (pixel footprints from its ray differentials, view,
// light and half-vector directions, shadowing) and prints, per `fabric =` object, each section
// or lobe as kept, left out or reduced with the reason. Reads the scene and its fabrics, writes
// nothing. Exit codes: 1 bad options, 2 a bad scene or fabric.
#include <algorithm>
#include <cstdio>
#include <memory>

#include "bake/cli/command.hpp"
#include "bake/cli/options.hpp"
#include "bake/inputs/terminal_text.hpp"
#include "bake/reports/scene_plan.hpp"

namespace clothbake::cli {
namespace {

struct PlanCliOptions {
  std::string scene;
  bool json = false;
};

int run_plan(const PlanCliOptions& o) {
  const inputs::LoadedScene loaded = inputs::load_scene(o.scene);
  const reports::ScenePlan plan = reports::plan_scene(loaded);
  if (o.json) {
    print_json(reports::plan_json(plan));
    return 0;
  }
  std::printf("plan for %s (error budget %.3g %%)\n", terminal_safe(plan.scene).c_str(),
              100 * plan.max_error);
  if (plan.fabrics.empty()) std::printf("  no object names a fabric: nothing to plan\n");
  for (const reports::FabricPlan& p : plan.fabrics) {
    const render::ObjectUsage& u = p.usage;
    std::printf("%s: %s (%d^2 texels)\n", terminal_safe(p.object_name).c_str(),
                terminal_safe(p.fabric_path).c_str(), p.resolution);
    std::printf(
        "  %llu pixels; footprints %.3g / %.3g / %.3g / %.3g texels (min / 5%% / median / "
        "max)\n",
        static_cast<unsigned long long>(u.pixels), u.footprint_min, u.footprint_p05,
        u.footprint_median, u.footprint_max);
    for (const auto& d : p.decisions)
      std::printf("  %-28s %-9s %s\n", d.item.c_str(), d.decision.c_str(),
                  terminal_safe(d.reason).c_str());
    std::printf(
        "  estimate: %.3g MB and %.3g s baked with the plan, %.3g MB and %.3g s without "
        "(%.1fx smaller, %.1fx faster; sizes after entropy coding, modelled; measured stage "
        "rates)\n",
        1e-6 * double(p.estimate.planned_bytes), p.estimate.planned_seconds,
        1e-6 * double(p.estimate.full_bytes), p.estimate.full_seconds,
        double(p.estimate.full_bytes) / double(std::max<uint64_t>(p.estimate.planned_bytes, 1)),
        p.estimate.full_seconds / std::max(p.estimate.planned_seconds, 1e-9));
    for (const auto& w : p.warnings)
      std::printf("  warning: %s\n", terminal_safe(w).c_str());
  }
  return 0;
}

const bool plan_registered = register_command(
    {"plan", "what each fabric of a scene needs: sections and lobes kept, left out or reduced",
     [](CLI::App& app) -> Action {
       auto o = std::make_shared<PlanCliOptions>();
       app.add_option("SCENE", o->scene, "scene description (.toml, docs/scene-format.md)")
           ->required();
       add_json_flag(app, o->json);
       return [o] { return run_plan(*o); };
     }});

}  // namespace
}  // namespace clothbake::cli
