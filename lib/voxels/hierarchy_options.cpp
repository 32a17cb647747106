#include "voxels/hierarchy_options.hpp"

#include "common/error.hpp"
#include "voxels/grid_fields.hpp"

namespace qte::voxels {
namespace {

const char* kVoxelsHelp = "voxels per side of every grid";
const char* kBoundsHelp = "scene bounds: minimum corner and edge length in metres";
const char* kDepthsHelp = "coarse-to-fine depths";
const char* kOffsetHelp = "half edge of the grids of each depth below 0, metres (one per depth: 0.15,0.05 for 3)";

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

std::vector<cli::OptionSpec> scene_options() {
  const CoarseToFine published;
  return {{"voxels", "V", kVoxelsHelp, std::to_string(published.voxels())},
          {"bounds", "X,Y,Z,S", kBoundsHelp, "-0.3,-0.5,0.6,1.0"}};
}

GridBounds parse_scene(const cli::Arguments& args, int min_voxels, int max_voxels) {
  const int voxels = static_cast<int>(args.integer("voxels", min_voxels, max_voxels));
  return as_usage_error([&] { return GridBounds::parse(args.text("bounds"), voxels); });
}

std::vector<cli::OptionSpec> hierarchy_options() {
  std::vector<cli::OptionSpec> options = scene_options();
  options.insert(options.begin() + 1, {{"depths", "D", kDepthsHelp, "2"}, {"offset", "M[,M...]", kOffsetHelp, "0.15"}});
  return options;
}

CoarseToFine parse_hierarchy(const cli::Arguments& args, int min_voxels, int max_voxels) {
  CoarseToFine hierarchy;
  hierarchy.scene = parse_scene(args, min_voxels, max_voxels);
  hierarchy.depths = static_cast<int>(args.integer("depths", 1, 8));
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
  const auto agree = [&](const char* option, int checkpoint_value) {
    if (args.has(option) && args.integer(option, 1, 1 << 20) != checkpoint_value)
      throw UsageError(std::string("--") + option + " " + args.text(option) + " differs from the checkpoint's " +
                       std::to_string(checkpoint_value) + " (" + checkpoint + ")");
  };
  agree("voxels", voxels);
  agree("depths", depths);
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
