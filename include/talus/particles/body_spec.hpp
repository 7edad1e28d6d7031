#pragma once
// The region a body fills and how it is seeded: the particles layer's own input, which the scene
// reader fills in from `bodies[i]` (docs/scene-reference.md).
#include "talus/core/polygon.hpp"
#include "talus/core/types.hpp"

#include <string>

namespace talus {

/// How a body's box is read on a terrain grid: in physical (x, y, z) (the bed clips what lies below
/// it), or in the grid's (x, y, w), w = height above the bed (a layer of uniform vertical thickness
/// that follows the terrain; its cells are the grid's isoparametric cells).
enum class BoxFrame { Physical, Terrain };
/// The region a body fills: an axis-aligned box, or a prism (a polygon in the x-z plane extruded
/// over [y0, y1]; e.g. the sand wedge behind a flume gate). particles/body_shape.hpp tests points.
enum class BodyShapeKind { Box, Prism };

struct PrismSpec {
  PolygonPoints points;   // (x, z) vertices, a simple polygon, >= 3
  double y0 = 0.0, y1 = 0.0;
};

struct BodySpec {
  std::string name;
  int material = 0;                      // index into Scene::materials
  BodyShapeKind shape = BodyShapeKind::Box;
  /// The box filled with particles; for a prism its bounding box (the candidates seeding tests).
  Vec3 box_min = Vec3::Zero();
  Vec3 box_max = Vec3::Zero();
  BoxFrame frame = BoxFrame::Physical;   // grid.terrain only
  PrismSpec prism;                       // BodyShapeKind::Prism only
  int particles_per_cell = 2;            // n: n x n x n particles per cell
  Vec3 velocity = Vec3::Zero();          // initial velocity
};

const char* to_string(BodyShapeKind shape);

}  // namespace talus
