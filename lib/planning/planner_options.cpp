#include "planning/planner_options.hpp"

namespace qte::planning {

using cli::default_text;

cli::OptionSpec time_budget_option() {
  return {"time-budget", "S", "seconds RRT-Connect may search for a move before reporting timeout",
          default_text(PlannerOptions{}.time_budget_s)};
}

std::vector<cli::OptionSpec> planner_options() {
  const PlannerOptions d;
  return {
      time_budget_option(),
      {"velocity-scale", "F", "fraction of the joints' 180 deg/s to move at", default_text(d.velocity_scale)},
      {"acceleration", "A", "joint acceleration limit, rad/s^2", default_text(d.max_acceleration_rad_s2)},
      {"clearance", "M", "extra distance in metres kept from occupied voxels", default_text(d.collision.clearance_m)},
      {"resolution", "M", "OctoMap voxel size in metres", default_text(d.scene.resolution_m)},
      {"approach", "M",
       "grasps (moves that end closing an open gripper): plan to M metres back along the tool axis on the whole "
       "scene, then a straight line to the grasp; 0 plans to the grasp itself with the space around it free",
       default_text(d.approach_m)},
  };
}

PlannerOptions planner_options_from(const cli::Arguments& args) {
  PlannerOptions options;
  options.time_budget_s = args.real("time-budget", 0.001, 600);
  if (args.declared("velocity-scale")) {  // plan-path; demo-record has the time budget only
    options.velocity_scale = args.real("velocity-scale", 0.01, 1);
    options.max_acceleration_rad_s2 = args.real("acceleration", 0.1, 1000);
    options.collision.clearance_m = args.real("clearance", 0, 0.5);
    options.scene.resolution_m = args.real("resolution", 0.002, 0.1);
    options.approach_m = args.real("approach", 0, 0.3);
  }
  options.seed = args.seed();
  return options;
}

}  // namespace qte::planning
