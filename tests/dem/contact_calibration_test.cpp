// The spring formulas of Abe 1996 (eq. 21, 22, 30-31, 34, 53) and the 3D uniform-strain estimate:
// round trips, independent re-derivations from the contact law, and refusals.
#include "talus/core/error.hpp"
#include "talus/dem/contact_calibration.hpp"
#include "talus/dem/disc_contact.hpp"
#include "talus/dem/hex_lattice_stress.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <numbers>
#include <string>
#include <tuple>
#include <vector>

namespace talus::dem {
namespace contact_calibration_test {
namespace {

constexpr double kPi = std::numbers::pi;

PackingGeometry geometry_of(Packing packing) {
  PackingParameters parameters;
  if (is_three_dimensional(packing)) parameters.radius = 0.003;
  return make_packing_geometry(packing, parameters);
}

// ---- round trips: (G, nu) -> (kN, kT) -> (G, nu) --------------------------------------------------

struct RoundTripCase {
  Packing packing;
  PlaneCondition plane;
  double poisson;
};

class RoundTrip : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(RoundTrip, SpringsGiveBackTheTargetContinuum) {
  const RoundTripCase c = GetParam();
  const PackingGeometry geometry = geometry_of(c.packing);
  const IsotropicElasticity target = IsotropicElasticity::from_young(2.5e7, c.poisson);
  const ContactSprings springs = calibrate_contact_springs(target, geometry, c.plane);
  EXPECT_GT(springs.normal, 0.0);
  EXPECT_GE(springs.tangential, 0.0);
  const IsotropicElasticity back = macroscopic_elasticity(springs, geometry, c.plane);
  EXPECT_NEAR(back.shear_modulus / target.shear_modulus, 1.0, 1e-13);
  EXPECT_NEAR(back.poisson_ratio, target.poisson_ratio, 1e-13);
  EXPECT_NEAR(back.young_modulus() / target.young_modulus(), 1.0, 1e-13);
}

std::vector<RoundTripCase> round_trip_cases() {
  std::vector<RoundTripCase> cases;
  for (Packing packing : {Packing::hexagonal, Packing::hexagonal_rotation_locked, Packing::random_2d,
                          Packing::random_3d}) {
    for (double nu : {-0.5, -0.1, 0.0, 0.1, 0.2, 0.25}) {
      cases.push_back({packing, PlaneCondition::strain, nu});
      if (!is_three_dimensional(packing)) cases.push_back({packing, PlaneCondition::stress, nu});
    }
    if (!is_three_dimensional(packing)) cases.push_back({packing, PlaneCondition::stress, 1.0 / 3.0});
  }
  cases.push_back({Packing::square, PlaneCondition::strain, 0.0});
  cases.push_back({Packing::square, PlaneCondition::stress, 0.0});
  return cases;
}

std::string round_trip_name(const ::testing::TestParamInfo<RoundTripCase>& info) {
  std::string name(packing_name(info.param.packing));
  for (char& c : name) {
    if (c == '-') c = '_';
  }
  name += info.param.plane == PlaneCondition::stress ? "_plane_stress_nu_" : "_nu_";
  const long permille = std::lround(info.param.poisson * 1000.0);
  return name + (permille < 0 ? "minus_" : "") + std::to_string(std::labs(permille)) + "_permille";
}

INSTANTIATE_TEST_SUITE_P(AllPackings, RoundTrip, ::testing::ValuesIn(round_trip_cases()), round_trip_name);

// ---- the nu <-> kT/kN relations -------------------------------------------------------------------

TEST(ContactCalibration, PlaneStrainPoissonRatioIsEq22ForHexAndRandom2d) {
  for (Packing packing : {Packing::hexagonal, Packing::random_2d}) {
    for (double nu : {-0.4, 0.0, 0.125, 0.25}) {
      const ContactSprings k = calibrate_contact_springs({1.0e6, nu}, geometry_of(packing));
      EXPECT_NEAR(0.25 * (1.0 - k.tangential_to_normal()), nu, 1e-14);  // Abe 1996, eq. 22
    }
  }
}

TEST(ContactCalibration, Random3dPoissonRatioIsTheUniformStrainRelation) {
  for (double nu : {-0.4, 0.0, 0.125, 0.25}) {
    const double alpha = calibrate_contact_springs({1.0e6, nu}, geometry_of(Packing::random_3d)).tangential_to_normal();
    EXPECT_NEAR((1.0 - alpha) / (4.0 + alpha), nu, 1e-14);
  }
}

TEST(ContactCalibration, PlaneStressReadsNuAsNuOverOnePlusNu) {
  for (Packing packing : {Packing::hexagonal, Packing::hexagonal_rotation_locked, Packing::random_2d}) {
    const double nu = 0.3;
    const ContactSprings stress = calibrate_contact_springs({1.0e6, nu}, geometry_of(packing), PlaneCondition::stress);
    const ContactSprings strain = calibrate_contact_springs({1.0e6, nu / (1.0 + nu)}, geometry_of(packing));
    EXPECT_DOUBLE_EQ(stress.normal, strain.normal);
    EXPECT_DOUBLE_EQ(stress.tangential, strain.tangential);
  }
}

TEST(ContactCalibration, Random2dWithTheHexagonalContactDensityIsEq34) {
  // Eq. 34 is eq. 21 with psi = 3/pi and gamma/rho = pi/(2 sqrt3).
  PackingParameters hexagonal_like;
  hexagonal_like.density_ratio = kHexagonalDensityRatio;
  hexagonal_like.coordination = 6.0;
  const PackingGeometry random = make_packing_geometry(Packing::random_2d, hexagonal_like);
  for (double nu : {-0.2, 0.1, 0.25}) {
    const ContactSprings from_random = calibrate_contact_springs({3.0e6, nu}, random);
    const ContactSprings from_hex = calibrate_contact_springs({3.0e6, nu}, geometry_of(Packing::hexagonal));
    EXPECT_NEAR(from_random.normal / from_hex.normal, 1.0, 1e-14);
    EXPECT_NEAR(from_random.tangential, from_hex.tangential, 1e-14 * from_hex.normal);
  }
}

TEST(ContactCalibration, SpringsOfRandomPackingsScaleWithOneOverSolidFractionTimesContacts) {
  PackingParameters loose;
  loose.density_ratio = 0.42;
  loose.coordination = 3.0;
  const ContactSprings dense = calibrate_contact_springs({1.0e6, 0.2}, geometry_of(Packing::random_2d));
  const ContactSprings sparse =
      calibrate_contact_springs({1.0e6, 0.2}, make_packing_geometry(Packing::random_2d, loose));
  const double expected = (kDefaultRandom2dDensityRatio * kDefaultRandom2dCoordination) / (0.42 * 3.0);
  EXPECT_NEAR(sparse.normal / dense.normal, expected, 1e-13);
}

TEST(ContactCalibration, SquareLatticeHasKnEqualKtEqualE) {
  const double young = 7.0e6;
  const ContactSprings k =
      calibrate_contact_springs(IsotropicElasticity::from_young(young, 0.0), geometry_of(Packing::square));
  EXPECT_NEAR(k.normal / young, 1.0, 1e-15);  // Abe 1996, eq. 31
  EXPECT_DOUBLE_EQ(k.tangential, k.normal);
}

TEST(ContactCalibration, AtTheLimitTheTangentialSpringVanishes) {
  for (Packing packing : {Packing::hexagonal, Packing::hexagonal_rotation_locked, Packing::random_2d,
                          Packing::random_3d}) {
    const ContactSprings k = calibrate_contact_springs({1.0e6, poisson_ratio_limit(packing)}, geometry_of(packing));
    EXPECT_NEAR(k.tangential, 0.0, 1e-12 * k.normal) << packing_name(packing);
  }
  const ContactSprings k = calibrate_contact_springs({1.0e6, 1.0 / 3.0}, geometry_of(Packing::hexagonal),
                                                     PlaneCondition::stress);
  EXPECT_NEAR(k.tangential, 0.0, 1e-12 * k.normal);
}

// ---- independent re-derivation of the 2D formulas from the contact law ----------------------------
// A lattice whose discs follow u(x) = H x + Q[x][x]/2 (rotation theta = curl u / 2, which balances
// every disc's moments for such a field) must feel, per disc, the force density of the continuum:
// sum F / (area per disc) = G lap u + G/(1 - 2 nu) grad div u (Abe 1996, eq. 19). No Taylor series is
// truncated for a quadratic field, so the two agree to rounding error when the springs are right.

struct QuadraticField {
  Mat2 gradient_at_origin;
  Mat2 second[2];  // second[j](m, n) = d2 u_j / dx_m dx_n

  Vec2 displacement(const Vec2& x) const {
    Vec2 u = gradient_at_origin * x;
    for (int j = 0; j < 2; ++j) u[j] += 0.5 * x.dot(second[j] * x);
    return u;
  }
  double rotation(const Vec2& x) const {  // (du2/dx1 - du1/dx2)/2
    return 0.5 * (gradient_at_origin(1, 0) + second[1].row(0).dot(x) - gradient_at_origin(0, 1) -
                  second[0].row(1).dot(x));
  }
  Vec2 continuum_force_density(double shear, double poisson) const {
    Vec2 f;
    for (int i = 0; i < 2; ++i) {
      const double laplacian = second[i].trace();
      const double grad_div = second[0](0, i) + second[1](1, i);
      f[i] = shear * laplacian + shear / (1.0 - 2.0 * poisson) * grad_div;
    }
    return f;
  }
};

QuadraticField sample_field(unsigned seed) {
  std::srand(seed);
  QuadraticField field;
  field.gradient_at_origin = Mat2::Random();
  for (auto& s : field.second) {
    const Mat2 r = Mat2::Random();
    s = r + r.transpose();
  }
  return field;
}

Vec2 lattice_force_density(const ContactSprings& springs, const std::vector<Vec2>& normals, double radius,
                           double area_per_disc, const QuadraticField& field, bool rotations_locked,
                           double* moment_sum = nullptr) {
  Vec2 force = Vec2::Zero();
  double moments = 0.0;
  const Vec2 origin = Vec2::Zero();
  const double theta_a = rotations_locked ? 0.0 : field.rotation(origin);
  for (const Vec2& n : normals) {
    const Vec2 neighbour = 2.0 * radius * n;
    const double theta_b = rotations_locked ? 0.0 : field.rotation(neighbour);
    const ContactLoad load =
        contact_load(springs, n, field.displacement(neighbour) - field.displacement(origin), theta_a, theta_b, radius);
    force += load.force;
    moments += load.moment;
  }
  if (moment_sum) *moment_sum = moments;
  return force / area_per_disc;
}

std::vector<Vec2> evenly_spaced_normals(int count, double offset) {
  std::vector<Vec2> normals;
  for (int k = 0; k < count; ++k) {
    const double angle = offset + 2.0 * kPi * k / count;
    normals.push_back({std::cos(angle), std::sin(angle)});
  }
  return normals;
}

void expect_lattice_matches_continuum(const ContactSprings& springs, const std::vector<Vec2>& normals,
                                      double radius, double area_per_disc, bool rotations_locked,
                                      const IsotropicElasticity& target) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const QuadraticField field = sample_field(seed);
    double moments = 0.0;
    const Vec2 lattice = lattice_force_density(springs, normals, radius, area_per_disc, field, rotations_locked, &moments);
    const Vec2 continuum = field.continuum_force_density(target.shear_modulus, target.poisson_ratio);
    EXPECT_LT((lattice - continuum).norm(), 1e-12 * target.shear_modulus * 10.0)
        << "lattice " << lattice.transpose() << " continuum " << continuum.transpose();
    if (!rotations_locked) {
      EXPECT_NEAR(moments, 0.0, 1e-12 * springs.normal * radius * radius);
    }
  }
}

TEST(ContactCalibration, HexagonalSpringsReproduceTheNavierEquation) {
  const double radius = 0.01;
  const double area = 2.0 * std::sqrt(3.0) * radius * radius;  // pi a^2 / (gamma/rho)
  const auto hex = hexagonal_contact_normals();
  const std::vector<Vec2> normals(hex.begin(), hex.end());
  for (double nu : {-0.3, 0.0, 0.15, 0.25}) {
    const IsotropicElasticity target{4.0e6, nu};
    expect_lattice_matches_continuum(calibrate_contact_springs(target, geometry_of(Packing::hexagonal)), normals,
                                     radius, area, false, target);
    expect_lattice_matches_continuum(
        calibrate_contact_springs(target, geometry_of(Packing::hexagonal_rotation_locked)), normals, radius, area,
        true, target);
  }
}

TEST(ContactCalibration, LockedRotationsNeedEq53NotEq34) {
  // The same check fails when the free-rotation springs are used on a locked lattice, so the
  // comparison above can tell the two models apart.
  const double radius = 1.0;
  const auto hex = hexagonal_contact_normals();
  const std::vector<Vec2> normals(hex.begin(), hex.end());
  const IsotropicElasticity target{1.0, 0.1};
  const ContactSprings eq34 = calibrate_contact_springs(target, geometry_of(Packing::hexagonal));
  const QuadraticField field = sample_field(7);
  const Vec2 lattice = lattice_force_density(eq34, normals, radius, 2.0 * std::sqrt(3.0), field, true);
  EXPECT_GT((lattice - field.continuum_force_density(1.0, 0.1)).norm(), 1e-3);
}

TEST(ContactCalibration, SquareLatticeSpringsReproduceTheNavierEquationForNuZero) {
  const double radius = 0.5;
  const IsotropicElasticity target = IsotropicElasticity::from_young(3.0e6, 0.0);
  expect_lattice_matches_continuum(calibrate_contact_springs(target, geometry_of(Packing::square)),
                                   evenly_spaced_normals(4, 0.0), radius, 4.0 * radius * radius, false, target);
}

TEST(ContactCalibration, Random2dSpringsReproduceTheNavierEquationForAnIsotropicContactFan) {
  // A disc with Z evenly spaced contacts (any orientation) stands for an isotropic packing of
  // solid fraction phi when it represents an area pi a^2 / phi.
  const double radius = 0.2;
  for (const auto& [phi, contacts, offset] : {std::tuple{0.84, 6, 0.3}, std::tuple{0.7, 8, 1.1},
                                               std::tuple{0.5, 10, 0.0}}) {
    PackingParameters parameters;
    parameters.density_ratio = phi;
    parameters.coordination = contacts;
    const PackingGeometry geometry = make_packing_geometry(Packing::random_2d, parameters);
    for (double nu : {-0.2, 0.2}) {
      const IsotropicElasticity target{2.0e6, nu};
      expect_lattice_matches_continuum(calibrate_contact_springs(target, geometry),
                                       evenly_spaced_normals(contacts, offset), radius,
                                       kPi * radius * radius / phi, false, target);
    }
  }
}

// ---- independent check of the 3D uniform-strain estimate -------------------------------------------
// Love's formula sigma = (1/V) sum_contacts f l^T with f = kN (n.d) n + kT (d - (n.d) n), d = eps l,
// over contact directions along the 12 vertices of an icosahedron (a spherical 5-design, so its
// fourth moments are those of an isotropic distribution) must give lambda tr(eps) I + 2 mu eps.

TEST(ContactCalibration, Random3dSpringsGiveTheTargetUnderUniformStrain) {
  const double golden = 0.5 * (1.0 + std::sqrt(5.0));
  std::vector<Eigen::Vector3d> directions;
  for (double p : {-1.0, 1.0}) {
    for (double q : {-golden, golden}) {
      directions.push_back(Eigen::Vector3d(0.0, p, q).normalized());
      directions.push_back(Eigen::Vector3d(p, q, 0.0).normalized());
      directions.push_back(Eigen::Vector3d(q, 0.0, p).normalized());
    }
  }
  ASSERT_EQ(directions.size(), 12u);

  PackingParameters parameters;
  parameters.radius = 2.0e-3;
  parameters.density_ratio = 0.6;
  parameters.coordination = 5.5;
  const PackingGeometry geometry = make_packing_geometry(Packing::random_3d, parameters);
  const double a = geometry.radius;
  const double particles_per_volume = geometry.density_ratio / (4.0 / 3.0 * kPi * a * a * a);

  for (double nu : {-0.3, 0.1, 0.25}) {
    const IsotropicElasticity target = IsotropicElasticity::from_young(5.0e7, nu);
    const ContactSprings k = calibrate_contact_springs(target, geometry);
    Eigen::Matrix3d strain = Eigen::Matrix3d::Random();
    strain = 0.5 * (strain + strain.transpose()).eval();

    Eigen::Matrix3d stress = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& n : directions) {
      const Eigen::Vector3d branch = 2.0 * a * n;
      const Eigen::Vector3d opening = strain * branch;
      const double normal_part = n.dot(opening);
      const Eigen::Vector3d force = k.normal * normal_part * n + k.tangential * (opening - normal_part * n);
      stress += force * branch.transpose();
    }
    // Each particle has Z contacts spread over the 12 directions; each contact is shared by two.
    stress *= particles_per_volume * geometry.coordination / 12.0 / 2.0;

    const double mu = target.shear_modulus;
    const double lambda = 2.0 * mu * nu / (1.0 - 2.0 * nu);
    const Eigen::Matrix3d expected = lambda * strain.trace() * Eigen::Matrix3d::Identity() + 2.0 * mu * strain;
    EXPECT_LT((stress - expected).norm(), 1e-12 * expected.norm()) << "nu = " << nu;
  }
}

// ---- refusals -------------------------------------------------------------------------------------

void expect_refusal(const std::function<void()>& call, const std::vector<std::string>& fragments) {
  try {
    call();
    ADD_FAILURE() << "expected talus::Error";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_code(), 2);
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    for (const std::string& fragment : fragments) {
      EXPECT_NE(message.find(fragment), std::string::npos) << "'" << fragment << "' not in: " << message;
    }
  }
}

TEST(ContactCalibrationRefusal, PoissonRatioAboveTheLimitIsRefusedNotAnsweredWithANegativeSpring) {
  for (Packing packing : {Packing::hexagonal, Packing::hexagonal_rotation_locked, Packing::random_2d,
                          Packing::random_3d}) {
    const PackingGeometry geometry = geometry_of(packing);
    expect_refusal([&] { calibrate_contact_springs({1.0e6, 0.2500001}, geometry); },
                   {"--nu = 0.2500001", "limit 0.25", std::string(packing_name(packing)), "kT >= 0"});
    EXPECT_NO_THROW(calibrate_contact_springs({1.0e6, 0.25}, geometry));
  }
  expect_refusal(
      [] { calibrate_contact_springs({1.0e6, 0.34}, geometry_of(Packing::hexagonal), PlaneCondition::stress); },
      {"--nu = 0.34", "limit 0.333333", "plane stress"});
  EXPECT_NO_THROW(calibrate_contact_springs({1.0e6, 0.33}, geometry_of(Packing::hexagonal), PlaneCondition::stress));
}

TEST(ContactCalibrationRefusal, SquareLatticeRefusesAnyNonZeroPoissonRatio) {
  for (double nu : {0.1, -0.1, 1e-9}) {
    expect_refusal([&] { calibrate_contact_springs({1.0e6, nu}, geometry_of(Packing::square)); },
                   {"--nu", "square", "only nu = 0"});
  }
  expect_refusal([] { macroscopic_elasticity({1.0, 0.5}, geometry_of(Packing::square)); }, {"not isotropic"});
}

TEST(ContactCalibrationRefusal, UnstableOrMeaninglessTargetsAreRefused) {
  const PackingGeometry hex = geometry_of(Packing::hexagonal);
  expect_refusal([&] { calibrate_contact_springs({1.0e6, -1.0}, hex); }, {"--nu = -1", "(-1, 0.5)"});
  expect_refusal([&] { calibrate_contact_springs({1.0e6, 0.5}, hex); }, {"--nu = 0.5", "(-1, 0.5)"});
  expect_refusal([&] { calibrate_contact_springs({1.0e6, NAN}, hex); }, {"--nu"});
  expect_refusal([&] { calibrate_contact_springs({0.0, 0.1}, hex); }, {"shear modulus", "> 0"});
  expect_refusal([&] { calibrate_contact_springs({1.0e6, 0.1}, geometry_of(Packing::random_3d), PlaneCondition::stress); },
                 {"--plane-stress", "random3d"});
}

TEST(ContactCalibrationRefusal, PackingParametersThatDoNotApplyAreRefused) {
  PackingParameters with_density;
  with_density.density_ratio = 0.9;
  expect_refusal([&] { make_packing_geometry(Packing::hexagonal, with_density); }, {"--density-ratio", "hex"});
  PackingParameters with_contacts;
  with_contacts.coordination = 4.0;
  expect_refusal([&] { make_packing_geometry(Packing::square, with_contacts); }, {"--coordination", "square"});
  PackingParameters with_radius;
  with_radius.radius = 0.01;
  expect_refusal([&] { make_packing_geometry(Packing::random_2d, with_radius); }, {"--radius", "random2d"});
  expect_refusal([&] { make_packing_geometry(Packing::random_3d, {}); }, {"--radius is required"});
  PackingParameters overfull;
  overfull.density_ratio = 1.2;
  overfull.radius = 0.01;
  expect_refusal([&] { make_packing_geometry(Packing::random_3d, overfull); }, {"--density-ratio = 1.2"});
  expect_refusal([] { parse_packing("hexagonal"); }, {"--packing", "hex, hex-locked, square, random2d, random3d"});
}

TEST(Packing, NamesRoundTrip) {
  for (Packing packing : {Packing::hexagonal, Packing::hexagonal_rotation_locked, Packing::square,
                          Packing::random_2d, Packing::random_3d}) {
    EXPECT_EQ(parse_packing(packing_name(packing)), packing);
  }
}

// A random packing with fewer contacts per grain than a rigid one has (d + 1) carries no load: 2.5
// in 2D and 3.5 in 3D (and 1e-300, which gave kN = 5e307) are refused; d + 1 itself is accepted. 0
// and less are refused with the same words (they said "must be > 0", as if 1 would do).
TEST(ContactCalibration, CoordinationBelowARigidPackingIsRefused) {
  for (const auto& [packing, low, fewest] : {std::tuple{Packing::random_2d, 2.5, 3.0}, std::tuple{Packing::random_3d, 3.5, 4.0},
                                             std::tuple{Packing::random_2d, 1e-300, 3.0}, std::tuple{Packing::random_3d, 0.0, 4.0},
                                             std::tuple{Packing::random_2d, -1.0, 3.0}}) {
    PackingParameters parameters;
    parameters.coordination = low;
    if (packing == Packing::random_3d) parameters.radius = 1e-3;
    expect_refusal([&] { (void)make_packing_geometry(packing, parameters); }, {"--coordination = ", "is below"});
    parameters.coordination = fewest;
    EXPECT_NO_THROW((void)make_packing_geometry(packing, parameters));
  }
}

}  // namespace
}  // namespace contact_calibration_test
}  // namespace talus::dem
