// episode-stats: observations to a CSV summary of their episodes (success rate with a Wilson
// interval, steps, return), one row per run so that runs concatenate into one table.
#include <iostream>

#include "cli/command.hpp"
#include "common/error.hpp"
#include "report/csv.hpp"
#include "report/episode_stats.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "episode-stats";
  u.summary = "summarise the episodes of observation streams as CSV";
  u.description = {
      "Reads record streams (files, or standard input when FILE is '-' or absent) and follows "
      "their 'obs' records, as sim-step writes them; every other record type (actions, "
      "trajectories, voxels) is ignored, so the log of a whole actor loop can be read as it is. "
      "An episode is the observations up to and including one whose 'terminal' is 1. Its "
      "success is that observation's 'success', its steps that observation's 'step' (next-best "
      "poses executed), its return the sum of 'reward' over its observations, and its seed, "
      "task and failure reason that observation's 'episode_seed', 'task' and 'failure' (each "
      "optional).",
      "Prints CSV on standard output: a header line and one row "
      "'episodes,successes,success_rate,ci95_low,ci95_high,mean_steps,mean_return'. The "
      "interval is the Wilson score interval at 95 % (z = 1.959964), which, unlike the normal "
      "approximation, stays within 0..1 and is meaningful for few episodes and for rates of 0 "
      "or 1. With no episodes the row reads 0 episodes, rate 0, interval 0..1 and means 0. "
      "--label adds a first column 'label' (a method name, say), --column NAME=VALUE adds "
      "named columns after it (a seed, a training step) and --no-header leaves the header "
      "out, so the rows of several runs append to one file that plot-curves(1) draws. With "
      "--per-episode one row per episode is printed instead: "
      "'episode,episode_seed,task,success,steps,return,failure' (after the same extra "
      "columns).",
      "An episode does not span files. Observations after the last terminal one of a file (an "
      "interrupted run), or before an observation with 'frame' 0 (a new reset), form an "
      "unfinished episode: it is not counted and a line on standard error says so. Text cells "
      "that hold a comma, a quote or a line break are quoted as RFC 4180 says.",
  };
  u.arguments = {cli::input_files()};
  u.options = {
      {"label", "TEXT", "add a first column 'label' holding TEXT to every row", ""},
      {"column", "NAME=VALUE", "add a column NAME holding VALUE to every row, after 'label'", "", true},
      {"no-header", "", "leave out the header line (to append rows to an existing CSV)", ""},
      {"per-episode", "", "print one row per episode instead of the summary", ""},
  };
  u.examples = {
      {"sim-step --task reach_target --episodes 25 < fifo | tee log.rec | qte-select "
       "--checkpoint ckpt/latest.rec | plan-path > fifo; episode-stats log.rec",
       "success rate of an evaluation run"},
      {"episode-stats --label qte --column seed=1 --column step=20000 --no-header eval.rec >> curves.csv",
       "append one row for method qte, seed 1, training step 20000 to a table for plot-curves "
       "--group label --x step --y success_rate"},
      {"episode-stats --per-episode log.rec | awk -F, '$4 == 0'",
       "the episodes that failed, with their seeds and reasons"},
  };
  u.see_also = {"sim-step(1)", "plot-curves(1)", "qte-stream(5)"};
  return u;
}

static void run(const cli::Arguments& args) {
  // The extra columns: --label first, then every --column in order (checked before any input
  // is read: a usage error must not wait for the end of a pipe).
  std::string extra_names, extra_values;
  if (args.has("label")) {
    extra_names += "label,";
    extra_values += report::csv_cell(args.text("label")) + ",";
  }
  for (const auto& [name, value] : args.assignments("column")) {
    extra_names += report::csv_cell(name) + ",";
    extra_values += report::csv_cell(value) + ",";
  }

  const std::vector<std::string> files = args.inputs();
  std::vector<report::Episode> episodes;
  for (const std::string& file : files) {
    const auto more = report::read_episodes(file, [](const std::string& line) {
      std::cerr << "episode-stats: " << line << "\n";
    });
    episodes.insert(episodes.end(), more.begin(), more.end());
  }
  const bool header = !args.flag("no-header");
  std::string out;
  if (args.flag("per-episode")) {
    if (header) out += extra_names + report::episode_csv_header();
    for (std::size_t i = 0; i < episodes.size(); ++i) out += extra_values + report::episode_csv_row(i, episodes[i]);
  } else {
    if (header) out += extra_names + report::summary_csv_header();
    out += extra_values + report::summary_csv_row(report::summarise_episodes(episodes));
  }
  std::cout << out;
  std::cout.flush();
  cli::check_standard_output();
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
