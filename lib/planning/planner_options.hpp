// The planner's command-line options, for plan-path (all of them) and demo-record (the time
// budget of the expert's moves). Defaults are PlannerOptions' own initial values (one home).
#pragma once

#include <vector>

#include "cli/command.hpp"
#include "planning/motion_planner.hpp"

namespace qte::planning {

cli::OptionSpec time_budget_option();  // --time-budget
// --time-budget, --velocity-scale, --acceleration, --clearance, --resolution.
std::vector<cli::OptionSpec> planner_options();
// The options above that were declared (range-checked), the rest PlannerOptions' defaults, and
// the seed.
PlannerOptions planner_options_from(const cli::Arguments& args);

}  // namespace qte::planning
