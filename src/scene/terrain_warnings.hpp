#pragma once
// What a terrain profile does to a run that the scene reader cannot refuse: a bed so steep that the
// sheared cells no longer bound the Courant step, and a profile with more detail than the grid
// resolves, along which the runout diagnostics would measure a longer bed than the particles slide on.
#include "talus/grid/grid.hpp"

#include <string>
#include <vector>

namespace talus {

/// Warnings for `grid.terrain` (none on a flat grid) at Courant number `courant`.
std::vector<std::string> terrain_warnings(const GridGeometry& grid, double courant);

}  // namespace talus
