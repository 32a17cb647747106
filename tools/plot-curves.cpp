// plot-curves: learning curves from CSV tables (episode-stats rows, training metrics) to PNG,
// mean over the rows at each x with a std or confidence band, one curve per group.
#include <array>
#include <tuple>

#include "cli/command.hpp"
#include "common/error.hpp"
#include "report/csv.hpp"
#include "report/curve_plot.hpp"
#include "report/curves.hpp"

using namespace qte;

static cli::Usage usage() {
  cli::Usage u;
  u.name = "plot-curves";
  u.summary = "draw learning curves from CSV tables as a PNG picture";
  u.description = {
      "Reads CSV tables (files, or standard input for '-'), each with a header line naming its "
      "columns (quoted cells as in RFC 4180; files may order their columns differently, and "
      "empty lines and lines repeating the header, as left by concatenating tables, are "
      "skipped), and draws column --y against column --x. Rows with the same value in column "
      "--group form one curve (e.g. the method: qte against c2farm), in the order in which "
      "the groups first appear; without --group all rows form one curve.",
      "Within a curve, the rows with the same x (several seeds, say) become one point, the "
      "mean of their y, drawn with a light translucent band: with --band std the mean +- "
      "their standard deviation (sample, n-1; no band where one row); with --band ci the "
      "means of their 'ci95_low' and 'ci95_high' columns where the table has them (as "
      "episode-stats(1) writes them), else the normal 95 % interval of the mean, mean +- "
      "1.96 std / sqrt(n); --band none draws the mean alone. Points are joined in increasing "
      "x.",
      "The picture has axes with ticks and numbers at round values, light grid lines, "
      "anti-aliased lines with a dot at every point, a distinct colour per curve (ten, then "
      "repeated) and, with --group, a legend of the group names in the emptiest corner. The "
      "axes span the data and bands with a small margin; --y-range fixes the y axis (0,1 for "
      "success rates; what lies outside is clipped). The same input and options give the same "
      "bytes. The PNG is written under a temporary name and renamed into place when complete.",
      "With --panel COLUMN the picture is small multiples: one plot per distinct value of "
      "COLUMN (a task, say), titled with it, in the order the values first appear, "
      "--panel-columns to a row under the --title. --size is then the size of one panel. The "
      "panels share the vertical axis and each spans its own horizontal extent (tasks train "
      "for different numbers of steps); a group has the same colour in every panel.",
      "A table without one of the columns asked for, a cell of --x, --y (or of the interval "
      "columns for --band ci) that is not a finite number, a row with the wrong number of "
      "cells, or no rows at all stop the program with one line naming the file, line and "
      "column, and no picture is written.",
  };
  u.arguments = {{"CSV", "tables to read in order; '-' is standard input", false, true}};
  u.options = {
      {"x", "COLUMN", "column of the horizontal axis, e.g. step", "", false, true},
      {"y", "COLUMN", "column of the vertical axis, e.g. success_rate", "", false, true},
      {"group", "COLUMN", "one curve per distinct value of COLUMN (e.g. label or method)", ""},
      {"band", "KIND", "band around each mean: std, ci or none", "std"},
      {"output", "FILE", "the PNG file to write", "", false, true},
      {"title", "T", "title above the plot", ""},
      {"x-label", "L", "label of the horizontal axis (default: the --x column)", ""},
      {"y-label", "L", "label of the vertical axis (default: the --y column)", ""},
      {"y-range", "LO,HI", "fix the vertical axis to LO..HI", ""},
      {"size", "WxH", "picture size in pixels (of each panel with --panel)", "800x500"},
      {"panel", "COLUMN", "one plot per distinct value of COLUMN (e.g. task), side by side", ""},
      cli::integer_option("panel-columns", "N", "panels to a row with --panel", "4", 1, 100),
  };
  u.examples = {
      {"plot-curves --x step --y success_rate --group label --band ci --y-range 0,1 "
       "--title reach_target --output curves.png curves.csv",
       "success rate against training step, one curve per method, from rows that "
       "episode-stats --label METHOD --column step=N --no-header appended"},
      {"plot-curves --x step --y mean_steps --group label --band none --output steps.png curves.csv",
       "the mean episode length of the same runs, means only"},
  };
  u.examples.push_back(
      {"plot-curves --x env_steps --y success_rate --group label --panel task --panel-columns 4 --size 560x360 "
       "--y-range 0,1 --title 'Task Set 1' --output tasks.png curves.csv",
       "one panel per task, both methods in each, as the paper's figures of learning curves"});
  u.see_also = {"episode-stats(1)"};
  return u;
}

static void run(const cli::Arguments& args) {
  report::CurveColumns columns{args.text("x"), args.text("y"), args.text("group"), args.text("panel")};
  const std::string output = args.text("output");
  const report::Band band =
      std::array{report::Band::std_dev, report::Band::ci, report::Band::none}[args.choice("band", {"std", "ci", "none"})];
  report::CurvePlotOptions plot;
  std::tie(plot.width_px, plot.height_px) = args.size("size", 200, 150, 10000, 10000);
  plot.fixed_y = args.has("y-range");
  if (plot.fixed_y) std::tie(plot.y_min, plot.y_max) = args.range("y-range");
  plot.title = args.text("title");
  plot.x_label = args.has("x-label") ? args.text("x-label") : columns.x;
  plot.y_label = args.has("y-label") ? args.text("y-label") : columns.y;
  plot.legend = !columns.group.empty();

  report::CurveBuilder curves(columns, band);
  for (const std::string& file : args.positional()) curves.add(report::read_csv(file));
  if (columns.panel.empty())
    report::save_curve_plot(output, curves.curves(), plot);
  else
    report::save_panel_plot(output, curves.panels(), plot, static_cast<int>(args.integer("panel-columns")));
}

int main(int argc, char** argv) { return cli::run_tool(argc, argv, usage(), run); }
