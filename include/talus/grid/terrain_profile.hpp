#pragma once
// TerrainProfile: the bed height z_b(x) of a flume or slope, uniform across the width (y).
// Piecewise linear through given vertices, with an optional circular transition of radius r at
// any interior vertex (a fillet tangent to both neighbouring segments). Outside the first and last
// vertex the end segments continue straight.
//
// It answers what the grid, the bed contact and the runout diagnostics need:
//   height(x)           z_b(x)
//   slope(x)            z_b'(x)        (dN/dx_phys = dN/dx - z_b'(x) dN/dw, docs/theory.md)
//   normal(x)           the bed's unit normal pointing up, out of the ground
//   arc_length(x)       s(x): distance along the bed from the first vertex (negative before it)
//   x_at_arc_length(s)  the inverse of arc_length
//   kinks()             the x of vertices without a transition (the slope jumps there)
// The profile must be a graph z_b(x): vertices strictly increasing in x, transitions that fit
// between their neighbours (checked; an input_error names what does not fit).
#include "talus/core/types.hpp"

#include <array>
#include <optional>
#include <vector>

namespace talus {

struct TerrainSpec {
  std::vector<std::array<double, 2>> points;  // (x, z) vertices, x strictly increasing, >= 2
  std::vector<double> radii;                  // per vertex; only interior ones used; 0 = sharp kink
  bool empty() const { return points.empty(); }
};

class TerrainProfile {
 public:
  TerrainProfile() = default;
  /// Throws input_error for a profile that is not a valid graph, naming the member ("points[2]:",
  /// "radii:"); the scene reader puts the key path in front.
  explicit TerrainProfile(const TerrainSpec& spec);

  double height(double x) const;
  double slope(double x) const;
  Vec3 normal(double x) const;
  double arc_length(double x) const;
  double x_at_arc_length(double s) const;
  /// x of the interior vertices that have no circular transition.
  const std::vector<double>& kinks() const { return kinks_; }
  /// x where the last straight segment begins: the end of the last transition (the tangent point of
  /// its fillet), or the last interior vertex when it is a sharp kink. For a flume that is the start
  /// of the runout plane. Empty for a one-segment profile.
  std::optional<double> last_segment_start() const;
  /// The lowest and highest bed height over [x0, x1].
  std::array<double, 2> height_range(double x0, double x1) const;
  const TerrainSpec& spec() const { return spec_; }

 private:
  // One piece of the profile over [x0, x1]: a straight line z = z0 + k (x - x0), or a circular arc
  // of centre (cx, cz) and radius r, below the centre (concave up, sign = -1) or above (sign = +1).
  struct Piece {
    double x0 = 0.0, x1 = 0.0;
    double s0 = 0.0;             // arc length at x0
    bool arc = false;
    double z0 = 0.0, k = 0.0;    // line
    double cx = 0.0, cz = 0.0, r = 0.0, sign = 0.0;  // arc
    double height(double x) const;
    double slope(double x) const;
    double length_to(double x) const;  // arc length from x0 to x (x may lie outside for end pieces)
    double x_at(double ds) const;      // inverse of length_to
  };
  const Piece& piece_at(double x) const;

  TerrainSpec spec_;
  std::vector<Piece> pieces_;
  std::vector<double> kinks_;
};

}  // namespace talus
