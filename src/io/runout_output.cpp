#include "talus/io/runout_output.hpp"

#include "talus/core/error.hpp"
#include "talus/grid/terrain.hpp"
#include "talus/io/atomic_file.hpp"
#include "talus/io/vtu_writer.hpp"

#include <fmt/core.h>
#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <vector>

namespace talus {

std::string runout_csv_header() {
  // (front_x ... tail_z came last, after front_velocity: readers that take the columns by position
  // read the first thirteen as before)
  return "time,step,mass,front,tail,s_min,s_max,centre_s,centre_x,centre_y,centre_z,centre_velocity_s,front_velocity,"
         "front_x,front_z,tail_x,tail_z";
}

std::string runout_csv_row(const RunoutSample& r) {
  // The shortest text that reads back to the same double: a restart continues from these rows
  // (the front velocity differences the last one), so they must round-trip exactly.
  return fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
                     r.time, r.step, r.mass, r.front, r.tail, r.s_min, r.s_max, r.centre_s, r.centre[0], r.centre[1],
                     r.centre[2], r.centre_velocity_s, r.front_velocity, r.front_x, r.front_z, r.tail_x, r.tail_z);
}

std::optional<RunoutSample> parse_runout_csv_row(const std::string& row) {
  std::vector<std::string> fields;
  std::stringstream in(row);
  for (std::string f; std::getline(in, f, ',');) fields.push_back(f);
  // 13 fields: a row written before front_x ... tail_z (the caller locates them, locate_front_and_tail)
  if (fields.size() != kRunoutCsvColumns && fields.size() != kRunoutCsvColumnsBeforeLocation) return std::nullopt;
  RunoutSample r;
  try {
    std::size_t k = 0;
    auto next = [&]() { return std::stod(fields[k++]); };
    r.time = next();
    r.step = std::stoll(fields[k++]);
    r.mass = next();
    r.front = next();
    r.tail = next();
    r.s_min = next();
    r.s_max = next();
    r.centre_s = next();
    for (int d = 0; d < 3; ++d) r.centre[d] = next();
    r.centre_velocity_s = next();
    r.front_velocity = next();
    const double none = std::numeric_limits<double>::quiet_NaN();
    const bool located = fields.size() == kRunoutCsvColumns;
    r.front_x = located ? next() : none;
    r.front_z = located ? next() : none;
    r.tail_x = located ? next() : none;
    r.tail_z = located ? next() : none;
  } catch (const std::exception&) {
    return std::nullopt;
  }
  return r;
}

std::string runout_result_json(const RunoutResult& r) {
  // (17 digits, as runout.csv: the value read back is the one computed; always a JSON number with a
  // fraction or exponent, so that a typed reader gets a float in every run: "time": 2 was an integer
  // where a run stopped earlier wrote a float; none (NaN) as null, which JSON has, not nan)
  auto number = [](double v) {
    if (!std::isfinite(v)) return std::string("null");
    std::string text = fmt::format("{:.17g}", v);
    if (text.find_first_of(".e") == std::string::npos) text += ".0";
    return text;
  };
  auto optional = [&](const std::optional<double>& v) { return v ? number(*v) : std::string("null"); };
  auto boolean = [](bool b) { return b ? "true" : "false"; };
  return fmt::format(
      "{{\"status\": \"{}\", \"final\": {}, \"time\": {}, \"step\": {}, \"front\": {}, \"tail\": {}, "
      "\"front_x\": {}, \"front_z\": {}, \"tail_x\": {}, \"tail_z\": {}, \"gate_s\": {}, \"gate_from_scene\": {}, \"from_gate\": {}, \"runout_plane_s\": {}, "
      "\"beyond_runout_plane\": {}, \"all_left_time\": {}, \"outflow_mass_share\": {}, "
      "\"outflow_mass_share_x_plus\": {}, \"limited_by_outflow\": {}, \"front_at_grid_end\": {}}}",
      r.status, boolean(r.final), number(r.time), r.step, number(r.front), number(r.tail), number(r.front_x),
      optional(r.front_z), number(r.tail_x), optional(r.tail_z), number(r.gate_s),
      boolean(r.gate_from_scene), number(r.from_gate), optional(r.runout_plane_s), optional(r.beyond_runout_plane),
      optional(r.all_left_time), number(r.outflow_mass_share), number(r.outflow_mass_share_x_plus),
      boolean(r.limited_by_outflow), boolean(r.front_at_grid_end));
}

void write_deposit_csv(const std::string& path, const DepositRaster& raster, const FlumeCoordinates& c) {
  std::string text = "s,y,x,thickness,thickness_seeded\n";
  text.reserve(text.size() + static_cast<std::size_t>(raster.ns) * raster.ny * 72);
  for (int i = 0; i < raster.ns; ++i) {
    const double s = raster.s_centre(i);
    const double x = c.x_at(s);
    for (int j = 0; j < raster.ny; ++j)
      text += fmt::format("{:.8e},{:.8e},{:.8e},{:.8e},{:.8e}\n", s, raster.y_centre(j), x, raster.at(i, j),
                          raster.seeded_at(i, j));
  }
  write_file_atomically(path, text);
}

void write_terrain_vtu(const std::string& path, const TerrainProfile& profile, double x0, double x1, double y0,
                       double y1, double max_segment, double column_spacing, double bed_w) {
  // The bed the particles meet, not the profile: at a convex crest or a kink between node columns the
  // profile drawn before lay up to 2 cm above the bed, and resting sand looked sunk into it (a user's
  // hunt, 2026-12-07). Sampled uniformly and at every node column, where the bed bends.
  const int columns = static_cast<int>(std::lround((x1 - x0) / column_spacing)) + 1;
  const ProfileTerrain bed(profile, x0, column_spacing, 0, columns);
  std::vector<double> xs;
  const int segments = std::max(1, static_cast<int>(std::ceil((x1 - x0) / max_segment)));
  for (int i = 0; i <= segments; ++i) xs.push_back(x0 + (x1 - x0) * i / segments);
  for (int i = 0; i < columns; ++i) xs.push_back(x0 + i * column_spacing);
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end(), [&](double a, double b) { return b - a < 1e-9 * column_spacing; }),
           xs.end());

  const auto n = static_cast<vtkIdType>(xs.size());
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(2 * n);
  vtkNew<vtkDoubleArray> arc, angle, above;
  arc->SetName("arc_length");
  arc->SetNumberOfTuples(2 * n);
  angle->SetName("slope_angle");
  angle->SetNumberOfTuples(2 * n);
  above->SetName("profile_above_bed");
  above->SetNumberOfTuples(2 * n);
  for (vtkIdType i = 0; i < n; ++i) {
    const double x = xs[i], z = bed.height(x) + bed_w;
    const double s = profile.arc_length(x);
    // positive where the bed descends in +x (+ 0.0: a flat bed read "-0" in ParaView's range)
    const double deg = std::atan(-profile.slope(x)) * 180.0 / M_PI + 0.0;
    for (int side = 0; side < 2; ++side) {
      points->SetPoint(2 * i + side, x, side == 0 ? y0 : y1, z);
      arc->SetValue(2 * i + side, s);
      angle->SetValue(2 * i + side, deg);
      above->SetValue(2 * i + side, profile.height(x) - z);
    }
  }
  vtkNew<vtkCellArray> cells;
  for (vtkIdType i = 0; i + 1 < n; ++i) {
    const vtkIdType quad[4] = {2 * i, 2 * (i + 1), 2 * (i + 1) + 1, 2 * i + 1};
    cells->InsertNextCell(4, quad);
  }
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  grid->SetCells(VTK_QUAD, cells);
  grid->GetPointData()->AddArray(arc);
  grid->GetPointData()->AddArray(angle);
  grid->GetPointData()->AddArray(above);
  write_vtu_atomically(grid, path, false, "terrain surface");
}

}  // namespace talus
