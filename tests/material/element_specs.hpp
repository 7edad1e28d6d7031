#pragma once
// Element-test specifications shared by the material tests.
#include "talus/material/element_test.hpp"

#include <utility>
#include <vector>

namespace talus::test {

/// One element test of material `p`: along `path` at `pressure` through the control-strain
/// `targets` in `increments` steps in all; every other setting (the simple-shear spin among them)
/// is ElementTestSpec's default.
inline ElementTestSpec element_spec(ElementPath path, const DruckerPragerParameters& p, double pressure,
                                    std::vector<double> targets, int increments) {
  ElementTestSpec s;
  s.material = p;
  s.path = path;
  s.pressure = pressure;
  s.strain_targets = std::move(targets);
  s.increments = increments;
  return s;
}

}  // namespace talus::test
