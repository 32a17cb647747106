#include "voxels/hierarchy_options.hpp"

#include "common/error.hpp"
#include "voxels/grid_fields.hpp"

namespace qte::voxels {
namespace {

const char* kVoxelsHelp = "voxels per side of every grid";
const char* kBoundsHelp = "scene bounds: minimum corner and edge length in metres";
const char* kDepthsHelp = "coarse-to-fine depths";
const char* kOffsetHelp = "half edge of the grids of each depth below 0, metres (one per depth: 0.15,0.05 for 3)";
constexpr int kMaxDepths = 8;

// Errors of the values (a negative offset, an offset count that does not match) are usage errors.
template <typename Parse>
auto as_usage_error(Parse parse) {
  try {
    return parse();
  } catch (const UsageError&) {
    throw;
  } catch (const Error& e) {
    throw UsageError(e.what());
  }
}

}  // namespace

// "-0.3,-0.5,0.6,1" (--bounds) or "0.15,0.05" (--offset): a default as those options take it.
std::string comma_separated(const std::vector<double>& values) {
  std::string text;
  for (double v : values) text += (text.empty() ? "" : ",") + cli::default_text(v);
  return text;
}

std::vector<cli::OptionSpec> scene_options() {
  const CoarseToFine published;
  return {{"voxels", "V", kVoxelsHelp, cli::default_text(published.voxels())},
          {"bounds", "X,Y,Z,S", kBoundsHelp, comma_separated(bounds_values(published.scene))}};
}

GridBounds parse_scene(const cli::Arguments& args, int min_voxels, int max_voxels) {
  const int voxels = static_cast<int>(args.integer("voxels", min_voxels, max_voxels));
  return as_usage_error([&] { return GridBounds::parse(args.text("bounds"), voxels); });
}

std::vector<cli::OptionSpec> hierarchy_options() {
  std::vector<cli::OptionSpec> options = scene_options();
  const CoarseToFine published;
  options.insert(options.begin() + 1,
                 {cli::integer_option("depths", "D", kDepthsHelp, cli::default_text(published.depths), 1, kMaxDepths),
                  {"offset", "M[,M...]", kOffsetHelp, comma_separated(published.offsets_m)}});
  return options;
}

CoarseToFine parse_hierarchy(const cli::Arguments& args, int min_voxels, int max_voxels) {
  CoarseToFine hierarchy;
  hierarchy.scene = parse_scene(args, min_voxels, max_voxels);
  hierarchy.depths = static_cast<int>(args.integer("depths"));
  hierarchy.offsets_m = as_usage_error([&] { return CoarseToFine::parse_offsets(args.text("offset"), hierarchy.depths); });
  return hierarchy;
}

std::vector<cli::OptionSpec> checkpoint_hierarchy_options() {
  std::vector<cli::OptionSpec> options = hierarchy_options();
  for (auto& o : options) {
    o.help += " (default: the checkpoint's" +
              (o.name == "bounds" || o.name == "offset" ? ", else " + o.default_value : std::string()) +
              "; must agree with it)";
    o.default_value.clear();
  }
  return options;
}

CoarseToFine checkpoint_hierarchy(const cli::Arguments& args, const std::optional<CoarseToFine>& trained, int voxels,
                                  int depths, const std::string& checkpoint) {
  const auto agree = [&](const char* option, int64_t given, int checkpoint_value) {
    if (given != checkpoint_value)
      throw UsageError(std::string("--") + option + " " + args.text(option) + " differs from the checkpoint's " +
                       std::to_string(checkpoint_value) + " (" + checkpoint + ")");
  };
  if (args.has("voxels")) agree("voxels", args.integer("voxels", 1, 1 << 20), voxels);  // the checkpoint says which
  if (args.has("depths")) agree("depths", args.integer("depths"), depths);
  CoarseToFine hierarchy = trained.value_or(CoarseToFine{});
  hierarchy.depths = depths;
  hierarchy.scene.voxels = voxels;
  const auto differs = [&](const char* option, const char* what) {
    return UsageError(std::string("--") + option + " " + args.text(option) + " differs from the " + what +
                      " the checkpoint was trained on (" + checkpoint + ")");
  };
  return as_usage_error([&] {
    if (args.has("bounds")) {
      const GridBounds given = GridBounds::parse(args.text("bounds"), voxels);
      if (trained && bounds_values(given) != bounds_values(hierarchy.scene)) throw differs("bounds", "bounds");
      hierarchy.scene = given;
    }
    if (args.has("offset")) {
      const std::vector<double> given = CoarseToFine::parse_offsets(args.text("offset"), depths);
      if (trained && given != hierarchy.offsets_m) throw differs("offset", "offsets");
      hierarchy.offsets_m = given;
    }
    hierarchy.validate();
    return hierarchy;
  });
}

}  // namespace qte::voxels
