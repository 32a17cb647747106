#include "planning/planner_options.hpp"

namespace qte::planning {

using cli::default_text;

cli::OptionSpec time_budget_option() {
  return cli::real_option("time-budget", "S", "seconds RRT-Connect may search for a move before reporting timeout",
                          default_text(PlannerOptions{}.time_budget_s), 0.001, 600);
}

std::vector<cli::OptionSpec> planner_options() {
  const PlannerOptions d;
  return {
      time_budget_option(),
      cli::real_option("velocity-scale", "F", "fraction of the joints' 180 deg/s to move at",
                       default_text(d.velocity_scale), 0.01, 1),
      cli::real_option("acceleration", "A", "joint acceleration limit, rad/s^2",
                       default_text(d.max_acceleration_rad_s2), 0.1, 1000),
      cli::real_option("clearance", "M", "extra distance in metres kept from occupied voxels",
                       default_text(d.collision.clearance_m), 0, 0.5),
      cli::real_option("resolution", "M", "OctoMap voxel size in metres", default_text(d.scene.resolution_m), 0.002,
                       0.1),
      cli::real_option(
          "approach", "M",
          "grasps (moves that end closing an open gripper): plan to M metres back along the tool axis on the whole "
          "scene, then a straight line to the grasp; 0 plans to the grasp itself with the space around it free",
          default_text(d.approach_m), 0, 0.3),
  };
}

PlannerOptions planner_options_from(const cli::Arguments& args) {
  PlannerOptions options;
  options.time_budget_s = args.real("time-budget");
  if (args.declared("velocity-scale")) {  // plan-path; demo-record has the time budget only
    options.velocity_scale = args.real("velocity-scale");
    options.max_acceleration_rad_s2 = args.real("acceleration");
    options.collision.clearance_m = args.real("clearance");
    options.scene.resolution_m = args.real("resolution");
    options.approach_m = args.real("approach");
  }
  options.seed = args.seed();
  return options;
}

}  // namespace qte::planning
