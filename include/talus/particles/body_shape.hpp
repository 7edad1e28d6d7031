#pragma once
// Which points a body fills: the inside test per body shape (body_spec.hpp BodyShapeKind). Seeding
// (seeding.cpp) lays candidate points over the body's bounding box and keeps those inside.
#include "talus/core/types.hpp"
#include "talus/particles/body_spec.hpp"

namespace talus {

/// Whether the physical point p = (x, y, z) belongs to the body. Half-open like a box's
/// [min, max): two bodies that share a face never both hold a point on it.
///   box:   min <= p < max on every axis;
///   prism: y0 <= y < y1 and (x, z) inside the polygon (core/polygon.hpp, crossing-number rule).
bool body_contains(const BodySpec& body, const Vec3& p);

}  // namespace talus
