#include "terrain_warnings.hpp"

#include "talus/grid/terrain_profile.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

namespace talus {

namespace {

constexpr double kDegrees = 180.0 / std::numbers::pi;
/// courant / cos(theta) above which a terrain is warned about: between the 1.44 that held and the
/// 1.73 that did not (terrain_warnings).
constexpr double kShearedCourantLimit = 1.5;

/// The bed the grid resolves: the profile sampled at the node columns x0 + i h, i = 0 .. cells, and
/// the chords between them (the cells shear with these chords, not with the profile between them,
/// and a segment of the profile outside the grid shears nothing).
struct ResolvedBed {
  double steepest_slope = 0.0;  // |dz/dx| of the steepest chord
  double steep_from = 0.0;      // the first column of the first chord steeper than the slope asked about
  double steep_to = 0.0;        // the last column of the last such chord
  double chord_length = 0.0;    // the chords' total length over the grid
  double profile_length = 0.0;  // the profile's arc length over the same columns
};

ResolvedBed resolved_bed(const TerrainProfile& profile, const GridGeometry& grid, double steep_slope) {
  ResolvedBed bed;
  const double h = grid.h;
  bool steep_seen = false;
  for (int i = 0; i < grid.cells[0]; ++i) {
    const double a = grid.origin[0] + i * h, b = a + h;
    const double rise = profile.height(b) - profile.height(a);
    bed.steepest_slope = std::max(bed.steepest_slope, std::abs(rise) / h);
    if (std::abs(rise) / h > steep_slope) {
      if (!steep_seen) bed.steep_from = a;
      steep_seen = true;
      bed.steep_to = b;
    }
    bed.chord_length += std::hypot(h, rise);
    bed.profile_length += profile.arc_length(b) - profile.arc_length(a);
  }
  return bed;
}

}  // namespace

std::vector<std::string> terrain_warnings(const GridGeometry& grid, double courant) {
  std::vector<std::string> warnings;
  if (!grid.has_terrain()) return warnings;
  // The cells shear with the bed: across its floor a cell is h cos(theta) high, and the step that
  // h bounds at time.courant is courant / cos(theta) of the step the sheared cell bounds. An elastic
  // block (inputs/terrain/incline30_coarse.json's, mu 0.3) slid down a 78-degree bed (courant 0.3:
  // 1.44) within 0.2% of the rigid block; on an 80-degree bed (1.73) it gained energy and stopped
  // after 32 steps, and a flume at 80 degrees ran to its end 2% further than at courant 0.15.
  const TerrainProfile profile(grid.terrain);
  // the slope above which courant / cos(theta) passes the limit (none when courant alone is past it)
  const double ratio = kShearedCourantLimit / courant;
  const double steep_slope = ratio > 1.0 ? std::sqrt(ratio * ratio - 1.0) : 0.0;
  const ResolvedBed bed = resolved_bed(profile, grid, steep_slope);
  const double steepest = bed.steepest_slope;
  const double cos_theta = 1.0 / std::sqrt(1.0 + steepest * steepest);
  // A spike between the node columns (a no-data value of -9999 at one point) is no steep chord, but
  // its two flanks are: name the point, which the runout's s along the profile then includes.
  constexpr double kStepSlope = 57.0;  // 89 degrees
  std::string step_point;
  const auto& points = grid.terrain.points;
  const double x_end = grid.origin[0] + grid.cells[0] * grid.h;
  for (std::size_t k = 0; k + 1 < points.size() && step_point.empty(); ++k)
    if (points[k + 1][0] > grid.origin[0] && points[k][0] < x_end &&
        std::abs(points[k + 1][1] - points[k][1]) > kStepSlope * (points[k + 1][0] - points[k][0]))
      step_point = fmt::format("grid.terrain.points[{}] to [{}], ({:.6g}, {:.6g}) to ({:.6g}, {:.6g})", k, k + 1,
                               points[k][0], points[k][1], points[k + 1][0], points[k + 1][1]);
  if (courant / cos_theta > kShearedCourantLimit) {
    // a value that keeps courant / cos(theta) at 1 or less: cos(theta) rounded down to 2 digits
    const double digit = std::pow(10.0, std::floor(std::log10(cos_theta)) - 1.0);
    warnings.push_back(fmt::format(
        "grid.terrain: between x = {:.6g} and {:.6g} m the bed the grid resolves (its node columns) slopes at up to "
        "{:.4g} degrees{}; the cells shear with it to {:.3g} h across their floors, and time.courant = {} is {:.3g} "
        "times the Courant step of such a cell. Runs at 1.44 held and at 1.73 gained energy and stopped "
        "(docs/theory.md, \"How steep\"): lower time.courant to {:.2g} or less",
        bed.steep_from, bed.steep_to, std::atan(steepest) * kDegrees,
        steepest > kStepSlope ? " (a no-data value or a step in the profile?)" : "", cos_theta, courant,
        courant / cos_theta, std::floor(cos_theta / digit) * digit));
  }
  if (!step_point.empty() && steepest <= kStepSlope)
    warnings.push_back(fmt::format(
        "{}: the profile rises or falls at more than 89 degrees between the grid's node columns (a no-data value or "
        "a step in the profile?); the particles slide on the bed sampled at the columns, but the runout diagnostics "
        "measure s along the whole profile",
        step_point));
  // w is measured from the profile and the bed is the z- face at w = origin[2]: any other origin
  // moves the bed off the profile (particles sat 0.16 m below the profile with origin[2] = -0.5;
  // terrain.vtu draws the bed where it is, since 2026-12-07).
  if (grid.origin[2] != 0.0)
    warnings.push_back(fmt::format(
        "grid.origin[2] = {} on a terrain grid: the bed (the z- face, w = origin[2]) lies {} m {} the profile of "
        "grid.terrain.points; give the bed's heights in the points and origin[2] = 0",
        grid.origin[2], std::abs(grid.origin[2]), grid.origin[2] < 0.0 ? "below" : "above"));
  // Outside its points the profile continues its end segments straight: a grid beyond them (an origin
  // in other coordinates than the points', a profile cut short) got a bed nobody gave, without a word.
  // (Up to a cell is the rounding of grid.size to whole cells.)
  const double x0 = grid.origin[0], x1 = x0 + grid.cells[0] * grid.h;
  const double first = grid.terrain.points.front()[0], last = grid.terrain.points.back()[0];
  const double before = first - x0, after = x1 - last;
  if (before > grid.h || after > grid.h)
    warnings.push_back(fmt::format(
        "grid.terrain.points cover x = [{:.6g}, {:.6g}] m and the grid x = [{:.6g}, {:.6g}] m: the bed continues the "
        "end segments straight over {}, where no point gives it; extend the points over the grid (or check "
        "grid.origin)",
        first, last, x0, x1,
        before > grid.h && after > grid.h ? fmt::format("{:.6g} m before the first point and {:.6g} m after the last", before, after)
        : before > grid.h                 ? fmt::format("{:.6g} m before the first point", before)
                                          : fmt::format("{:.6g} m after the last point", after)));
  // The particles slide on the profile sampled at the node columns (the chords between them); the
  // runout diagnostics measure s along the profile itself. Ripples finer than the cells made the
  // measured runout 18% longer than the resolved bed with the same motion.
  if (bed.profile_length > 1.01 * bed.chord_length)
    warnings.push_back(fmt::format(
        "grid.terrain has more detail than grid.cell_size = {} m resolves: over the grid the profile is {:.1f}% longer "
        "than the bed the grid samples at its node columns, on which the particles slide; the runout diagnostics "
        "measure s along the profile, so their distances come out that much longer. Sample the profile no finer "
        "than the cells, or refine the grid",
        grid.h, 100.0 * (bed.profile_length / bed.chord_length - 1.0)));
  // A kink between two node columns is cut by the chord between them (docs/scene-reference.md,
  // grid.terrain.radii: "put kinks on node columns or use r >= 2h"). Warned about, with r < 2h, where
  // the chord passes farther from the profile at the vertex than a transition of r = 2h departs from
  // its chords, h^2 / 8r = h / 16: a slight bend between columns, or a kink on a column, is not.
  for (std::size_t k = 1; k + 1 < points.size(); ++k) {
    const double xk = points[k][0];
    if (!(xk > grid.origin[0] && xk < x_end)) continue;
    const double left = grid.origin[0] + std::floor((xk - grid.origin[0]) / grid.h) * grid.h, right = left + grid.h;
    const double t = (xk - left) / grid.h;
    const double chord = (1.0 - t) * profile.height(left) + t * profile.height(right);
    const double off = std::abs(profile.height(xk) - chord);
    const double radius = k < grid.terrain.radii.size() ? grid.terrain.radii[k] : 0.0;
    if (radius >= 2.0 * grid.h || off <= grid.h / 16.0) continue;
    warnings.push_back(fmt::format(
        "grid.terrain.points[{}] = ({:.6g}, {:.6g}) is a {} between the node columns x = {:.6g} and {:.6g} m: the bed "
        "the grid resolves cuts it with the chord between them, {:.3g} m from the profile at the vertex (a transition "
        "of r = 2h departs h/16 = {:.3g} m); put the vertex on a node column or give it a radius of 2h = {:.6g} m or "
        "more (grid.terrain.radii[{}])",
        k, xk, points[k][1],
        radius > 0.0 ? fmt::format("transition of radius {} m, below 2h = {:.6g} m,", radius, 2.0 * grid.h)
                     : std::string("sharp kink (radius 0)"),
        left, right, off, grid.h / 16.0, 2.0 * grid.h, k));
  }
  return warnings;
}

}  // namespace talus
