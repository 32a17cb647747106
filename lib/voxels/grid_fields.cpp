#include "voxels/grid_fields.hpp"

#include "stream/field_names.hpp"

namespace qte::voxels {

std::vector<double> bounds_values(const GridBounds& b) {
  return {b.min_corner.x(), b.min_corner.y(), b.min_corner.z(), b.size_m};
}

GridBounds bounds_field(const stream::Record& record, const std::string& name, int voxels) {
  const auto v = record.array<double>(name);
  if (v.size() != 4 || !(v[3] > 0)) record.fail(name, "float64 [4]: minimum corner and a positive edge length");
  GridBounds b;
  b.min_corner = Eigen::Vector3d(v[0], v[1], v[2]);
  b.size_m = v[3];
  b.voxels = voxels;
  return b;
}

void set_hierarchy(stream::Record& record, const CoarseToFine& h) {
  record.set<double>(fields::hierarchy_bounds, {4}, bounds_values(h.scene));
  record.set<double>(fields::hierarchy_offsets, {static_cast<int64_t>(h.offsets_m.size())}, h.offsets_m);
  record.set_scalar<int32_t>(fields::hierarchy_depths, h.depths);
  record.set_scalar<int32_t>(fields::hierarchy_voxels, h.voxels());
}

std::optional<CoarseToFine> hierarchy_of(const stream::Record& record) {
  if (!record.has(fields::hierarchy_bounds)) return std::nullopt;
  CoarseToFine h;
  h.depths = record.scalar<int32_t>(fields::hierarchy_depths);
  h.scene = bounds_field(record, fields::hierarchy_bounds, record.scalar<int32_t>(fields::hierarchy_voxels));
  const auto offsets = record.array<double>(fields::hierarchy_offsets);
  h.offsets_m.assign(offsets.begin(), offsets.end());
  return h;
}

}  // namespace qte::voxels
