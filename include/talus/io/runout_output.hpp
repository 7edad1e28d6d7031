#pragma once
// The runout diagnostics' files (docs/flume.md): runout.csv, one row per history interval, and
// deposit.csv, the deposit thickness raster at the end of the run.
#include "talus/diagnostics/runout.hpp"

#include <cstddef>
#include <optional>
#include <string>

namespace talus {

/// time,step,mass,front,tail,s_min,s_max,centre_s,centre_x,centre_y,centre_z,centre_velocity_s,front_velocity,
/// front_x,front_z,tail_x,tail_z
std::string runout_csv_header();
inline constexpr std::size_t kRunoutCsvColumns = 17;
/// The columns of a runout.csv written before front_x ... tail_z were added (a restart reads it).
inline constexpr std::size_t kRunoutCsvColumnsBeforeLocation = 13;
/// One row; every number in the shortest form that reads back exactly (a restart continues from it).
std::string runout_csv_row(const RunoutSample& sample);
/// The inverse of runout_csv_row (a restart reads its history back); empty for a malformed row. A
/// row of the 13 older columns reads with front_x ... tail_z NaN: locate_front_and_tail fills them.
std::optional<RunoutSample> parse_runout_csv_row(const std::string& row);

/// The runout result as a JSON object (runout.json): status (run.json's), final (the run reached
/// time.end), time and step (of the front), front, tail, gate_s,
/// gate_from_scene, from_gate, and runout_plane_s, beyond_runout_plane where known, all_left_time
/// once every particle has left through the open faces (null otherwise), outflow_mass_share,
/// outflow_mass_share_x_plus, limited_by_outflow, front_at_grid_end.
std::string runout_result_json(const RunoutResult& result);

/// s,y,x,thickness: one row per raster cell (cell centres), s fastest-varying last (rows of constant s).
void write_deposit_csv(const std::string& path, const DepositRaster& raster, const FlumeCoordinates& coordinates);

/// The bed the particles slide on as a strip of quads over [y0, y1] (VTK_QUAD cells in a .vtu): the
/// profile sampled at the grid's node columns x0 + i column_spacing, straight between them, raised by
/// bed_w (the z- face's w, grid.origin[2]), as the terrain-following grid makes it (grid/terrain.hpp).
/// Sampled in x at spacing <= max_segment and at every node column, with point arrays "arc_length"
/// (the profile's s, the runout's coordinate), "slope_angle" [deg] (the profile's) and
/// "profile_above_bed" [m] (the profile's height over the drawn bed: where a transition or a kink
/// between node columns departs from it: up to h^2/(8 r cos^3 theta) on an arc, docs/theory.md).
void write_terrain_vtu(const std::string& path, const TerrainProfile& profile, double x0, double x1, double y0,
                       double y1, double max_segment, double column_spacing, double bed_w);

}  // namespace talus
