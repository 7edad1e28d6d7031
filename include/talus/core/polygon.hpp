#pragma once
// Plane polygons given by their vertices (a closed ring, the last vertex joined to the first): the
// cross-section of a prism body (scene bodies[i].prism, particles/body_shape.hpp).
#include <array>
#include <vector>

namespace talus {

using PolygonPoints = std::vector<std::array<double, 2>>;

/// Whether (a, b) lies inside the polygon, by the crossing-number (even-odd) rule with half-open
/// edges, so that of two polygons sharing an edge exactly one holds a point on it (the same
/// convention as a box's [min, max)). Works for any simple polygon, convex or not.
bool polygon_contains(const PolygonPoints& polygon, double a, double b);

/// Signed area (shoelace formula): positive for counter-clockwise vertices.
double polygon_signed_area(const PolygonPoints& polygon);

/// The first pair of edges (i, j), i < j, that touch although they are not neighbours, or that
/// overlap although they are neighbours; {-1, -1} for a simple polygon. Edge i joins vertex i to i + 1.
std::array<int, 2> polygon_crossing_edges(const PolygonPoints& polygon);

}  // namespace talus
