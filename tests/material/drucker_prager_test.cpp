// Verification of the Drucker–Prager model against closed forms (docs/drucker-prager.md, sec. 6).
// Stress positive in tension; Voigt order xx, yy, zz, yz, xz, xy with tensor shear components.
#include "element_specs.hpp"
#include "talus/core/error.hpp"
#include "talus/core/tensor.hpp"
#include "talus/material/drucker_prager.hpp"
#include "talus/material/element_test.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

namespace talus {
namespace drucker_prager_test {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;
using Regime = DruckerPragerResult::Regime;

// Largest value seen of a measured error; printed when the test ends, so that the numbers quoted
// in docs/drucker-prager.md come from running this suite.
class Worst {
 public:
  explicit Worst(const char* name) : name_(name) {}
  ~Worst() { std::printf("[ measured ] %s = %.2e\n", name_, value_); }
  double operator()(double v) {
    value_ = std::fmax(value_, std::abs(v));
    return v;
  }

 private:
  const char* name_;
  double value_ = 0.0;
};

DruckerPragerParameters sand(double phi = 30.0, double psi = 0.0, double c = 5.0e3) {
  DruckerPragerParameters p;
  p.young = 2.0e7;
  p.poisson = 0.3;
  p.friction_angle_deg = phi;
  p.dilatancy_angle_deg = psi;
  p.cohesion = c;
  return p;
}

double stress_scale(const Sym6& s, const DruckerPrager& m) {
  return std::max(s.cwiseAbs().maxCoeff(), m.initial_strength());
}

// Elastic strain of a stress change: C^-1 : d_sigma (isotropic, tensor components).
Sym6 elastic_strain(const DruckerPrager& m, const Sym6& d_sigma) {
  const double e = m.parameters().young, nu = m.parameters().poisson;
  Sym6 d_eps = (1.0 + nu) / e * d_sigma;
  const double vol = nu / e * trace(d_sigma);
  d_eps[XX] -= vol;
  d_eps[YY] -= vol;
  d_eps[ZZ] -= vol;
  return d_eps;
}

Sym6 random_sym6(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Sym6 s;
  for (int i = 0; i < 6; ++i) s[i] = scale * u(rng);
  return s;
}

/// sand(30 degrees, psi, c) with linear hardening of modulus `hardening_modulus`, split by Prager's
/// `kinematic_fraction` (0: isotropic, 1: kinematic): the material of the hardening tests.
DruckerPragerParameters hardening_sand(double psi, double c, double hardening_modulus, double kinematic_fraction) {
  DruckerPragerParameters p = sand(30.0, psi, c);
  p.hardening_modulus = hardening_modulus;
  p.kinematic_fraction = kinematic_fraction;
  return p;
}

Mat3 random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

Sym6 rotate(const Mat3& q, const Sym6& s) { return from_matrix(q * to_matrix(s) * q.transpose()); }

/// test::element_spec with the simple-shear spin switched off (no Jaumann rotation of the stress).
ElementTestSpec spec_for(ElementPath path, const DruckerPragerParameters& p, double pressure,
                         std::vector<double> targets, int increments) {
  ElementTestSpec s = test::element_spec(path, p, pressure, std::move(targets), increments);
  s.spin = false;
  return s;
}

std::size_t first_plastic(const std::vector<ElementTestPoint>& pts) {
  for (std::size_t i = 0; i < pts.size(); ++i)
    if (pts[i].regime != Regime::Elastic) return i;
  return pts.size();
}

// ---- parameters ---------------------------------------------------------------------------------

TEST(DruckerPragerParameters, RejectsOutOfRangeValuesNamingKeyAndRange) {
  struct Case {
    const char* key;
    void (*set)(DruckerPragerParameters&);
  };
  const Case cases[] = {
      {"young", [](DruckerPragerParameters& p) { p.young = 0.0; }},
      {"young", [](DruckerPragerParameters& p) { p.young = std::nan(""); }},
      {"poisson", [](DruckerPragerParameters& p) { p.poisson = 0.5; }},
      {"poisson", [](DruckerPragerParameters& p) { p.poisson = -0.1; }},
      {"friction_angle", [](DruckerPragerParameters& p) { p.friction_angle_deg = 0.0; }},
      {"friction_angle", [](DruckerPragerParameters& p) { p.friction_angle_deg = 90.0; }},
      {"dilatancy_angle", [](DruckerPragerParameters& p) { p.dilatancy_angle_deg = 31.0; }},
      {"dilatancy_angle", [](DruckerPragerParameters& p) { p.dilatancy_angle_deg = -1.0; }},
      {"cohesion", [](DruckerPragerParameters& p) { p.cohesion = -1.0; }},
      {"hardening_modulus", [](DruckerPragerParameters& p) { p.hardening_modulus = -1.0; }},
      {"kinematic_fraction", [](DruckerPragerParameters& p) { p.kinematic_fraction = 1.5; }},
      {"tension_cutoff", [](DruckerPragerParameters& p) { p.tension_cutoff = -1.0; }},
  };
  for (const Case& c : cases) {
    DruckerPragerParameters p = sand();
    c.set(p);
    try {
      DruckerPrager model(p, "bodies[0].material.");
      ADD_FAILURE() << c.key << ": no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), Error::Kind::Input);
      const std::string what = e.what();
      EXPECT_NE(what.find(std::string("bodies[0].material.") + c.key + " = "), std::string::npos)
          << what;
      EXPECT_NE(what.find("allowed"), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
  EXPECT_NO_THROW(DruckerPrager(sand(30.0, 30.0, 0.0)));  // psi = phi and c = 0 are allowed
}

TEST(DruckerPragerParameters, ConeFitsMatchMohrCoulombOnTheirMeridians) {
  const double phi = 35.0 * kDeg, c = 2.0e3;
  const double s = std::sin(phi);
  double a = 0, k = 0;
  // Compression and extension cones: f = 0 at the MC triaxial compression / extension states.
  for (ConeFit fit : {ConeFit::Compression, ConeFit::Extension}) {
    DruckerPrager::cone_coefficients(fit, 35.0, c, a, k);
    const double p0 = 1.0e4;
    const bool compression = fit == ConeFit::Compression;
    // MC (compression positive): sigma1 - sigma3 = 2 c cos(phi) + (sigma1 + sigma3) sin(phi).
    const double q = compression ? (2.0 * c * std::cos(phi) + 2.0 * p0 * s) / (1.0 - s)
                                 : (2.0 * c * std::cos(phi) + 2.0 * p0 * s) / (1.0 + s);
    Sym6 sig = -p0 * identity6();
    sig[YY] += compression ? -q : q;  // axial stress, tension positive
    EXPECT_NEAR(a * trace(sig) + std::sqrt(j2(sig)) - k, 0.0, 1e-12 * p0);
  }
  // Inscribed cone: its radius is the smallest MC radius over the Lode angle.
  DruckerPrager::cone_coefficients(ConeFit::Inscribed, 35.0, c, a, k);
  double min_ratio = 1e300;
  for (int i = 0; i <= 200000; ++i) {
    const double theta = -kPi / 6.0 + kPi / 3.0 * i / 200000.0;
    // MC at I1 = 0: sqrt(J2) (cos theta - sin theta sin phi / sqrt 3) = c cos phi.
    min_ratio = std::fmin(min_ratio, c * std::cos(phi) / (std::cos(theta) - std::sin(theta) * s / std::sqrt(3.0)));
  }
  EXPECT_NEAR(k, min_ratio, 1e-9 * k);
  // Plane strain: alpha = tan(phi)/sqrt(9 + 12 tan^2 phi), k = 3c/sqrt(9 + 12 tan^2 phi).
  DruckerPrager::cone_coefficients(ConeFit::PlaneStrain, 35.0, c, a, k);
  const double t = std::tan(phi);
  EXPECT_DOUBLE_EQ(a, t / std::sqrt(9.0 + 12.0 * t * t));
  EXPECT_DOUBLE_EQ(k, 3.0 * c / std::sqrt(9.0 + 12.0 * t * t));
  // Default is plane strain; alpha_g uses the same fit with psi.
  DruckerPrager model(sand(35.0, 10.0, c));
  EXPECT_EQ(model.parameters().cone, ConeFit::PlaneStrain);
  const double tg = std::tan(10.0 * kDeg);
  EXPECT_DOUBLE_EQ(model.alpha_dilatancy(), tg / std::sqrt(9.0 + 12.0 * tg * tg));
}

// ---- yield onset --------------------------------------------------------------------------------

TEST(DruckerPragerYield, TriaxialCompressionOnsetMatchesTheory) {
  const double p0 = 5.0e4, c = 5.0e3, phi = 30.0;
  Worst worst("triaxial compression: |q - q_DP| / p0 after yield, 4 cone fits");
  Worst worst_mc("compression cone: |q_DP - q_MC| / q_MC");
  for (ConeFit fit : {ConeFit::PlaneStrain, ConeFit::Compression, ConeFit::Extension, ConeFit::Inscribed}) {
    DruckerPragerParameters p = sand(phi, 0.0, c);
    p.cone = fit;
    const DruckerPrager model(p);
    const auto pts = run_element_test(spec_for(ElementPath::DrainedTriaxial, p, p0, {0.02}, 400));
    const std::size_t i = first_plastic(pts);
    ASSERT_LT(i, pts.size() - 10);
    // DP closed form (perfect plasticity: the deviator stays at the onset value).
    const double q_dp = (model.initial_strength() + 3.0 * model.alpha() * p0) / (1.0 / std::sqrt(3.0) - model.alpha());
    const double q_elastic = pts[i - 1].stress[XX] - pts[i - 1].stress[YY];
    EXPECT_LT(q_elastic, q_dp);
    for (std::size_t j = i; j < pts.size(); ++j) {
      worst((pts[j].stress[XX] - pts[j].stress[YY] - q_dp) / p0);
      ASSERT_NEAR(pts[j].stress[XX] - pts[j].stress[YY], q_dp, 1e-10 * p0) << "step " << j;
    }
    if (fit == ConeFit::Compression) {  // Mohr–Coulomb in triaxial compression
      const double s = std::sin(phi * kDeg);
      const double q_mc = (2.0 * c * std::cos(phi * kDeg) + 2.0 * p0 * s) / (1.0 - s);
      worst_mc((q_dp - q_mc) / q_mc);
      EXPECT_NEAR(q_dp, q_mc, 1e-12 * q_mc);
    }
  }
}

TEST(DruckerPragerYield, TriaxialExtensionOnsetMatchesMohrCoulombForExtensionCone) {
  const double p0 = 5.0e4, c = 5.0e3, phi = 30.0;
  DruckerPragerParameters p = sand(phi, 0.0, c);
  p.cone = ConeFit::Extension;
  const auto pts = run_element_test(spec_for(ElementPath::DrainedTriaxial, p, p0, {-0.02}, 400));
  const std::size_t i = first_plastic(pts);
  ASSERT_LT(i, pts.size() - 10);
  const double s = std::sin(phi * kDeg);
  const double q_mc = (2.0 * c * std::cos(phi * kDeg) + 2.0 * p0 * s) / (1.0 + s);
  Worst worst("extension cone, triaxial extension: |q - q_MC| / p0 after yield");
  for (std::size_t j = i; j < pts.size(); ++j) {
    worst((pts[j].stress[YY] - pts[j].stress[XX] - q_mc) / p0);
    ASSERT_NEAR(pts[j].stress[YY] - pts[j].stress[XX], q_mc, 1e-10 * p0) << "step " << j;
  }
}

TEST(DruckerPragerYield, SimpleShearOnsetMatchesTheory) {
  // Isotropic start, psi = 0: the shear stress stays at tau = k + 3 alpha p0 (DP, Lode angle 0).
  const double p0 = 2.0e4;
  Worst worst("simple shear onset: |tau - (k + 3 alpha p0)| / p0 after yield, 3 cone fits");
  for (ConeFit fit : {ConeFit::PlaneStrain, ConeFit::Compression, ConeFit::Inscribed}) {
    DruckerPragerParameters p = sand(35.0, 0.0, 3.0e3);
    p.cone = fit;
    const DruckerPrager model(p);
    const auto pts = run_element_test(spec_for(ElementPath::SimpleShear, p, p0, {0.02}, 200));
    const std::size_t i = first_plastic(pts);
    ASSERT_LT(i, pts.size() - 10);
    const double tau_y = model.initial_strength() + 3.0 * model.alpha() * p0;
    EXPECT_LT(pts[i - 1].stress[XY], tau_y);
    for (std::size_t j = i; j < pts.size(); ++j) {
      worst((pts[j].stress[XY] - tau_y) / p0);
      ASSERT_NEAR(pts[j].stress[XY], tau_y, 1e-10 * p0);
      ASSERT_NEAR(pts[j].stress[XX], -p0, 1e-10 * p0);  // no dilatancy: lateral stress unchanged
    }
  }
}

TEST(DruckerPragerYield, AssociatedSteadySimpleShearIsMohrCoulombInPlaneStrain) {
  // Plane-strain cone, psi = phi: at steady flow (eps_zz = 0, stresses constant) the in-plane
  // stresses satisfy Mohr–Coulomb, R = c cos(phi) + s_m sin(phi) with s_m = -(sxx + syy)/2.
  const double phi = 40.0, c = 1.0e3;
  const auto pts =
      run_element_test(spec_for(ElementPath::SimpleShear, sand(phi, phi, c), 1.0e4, {1.5}, 1500));
  const Sym6& s = pts.back().stress;
  const double radius = std::hypot(0.5 * (s[XX] - s[YY]), s[XY]);
  const double mc = c * std::cos(phi * kDeg) - 0.5 * (s[XX] + s[YY]) * std::sin(phi * kDeg);
  Worst("associated steady simple shear: |R - (c cos phi + s_m sin phi)| / R")((radius - mc) / radius);
  EXPECT_NEAR(radius, mc, 1e-10 * radius);
}

// ---- plastic flow direction ---------------------------------------------------------------------

TEST(DruckerPragerFlow, TriaxialDilatancyRatioMatchesPsi) {
  // Compression cone: d eps_v^p / d eps_q^p = 3 sqrt(3) alpha_g = 6 sin(psi)/(3 - sin(psi)).
  Worst worst("triaxial: |d eps_v^p / d eps_q^p - 6 sin psi / (3 - sin psi)|, psi = 0, 10, 30 = phi");
  for (double psi : {0.0, 10.0, 30.0 /* = phi: associated */}) {
    DruckerPragerParameters p = sand(30.0, psi, 5.0e3);
    p.cone = ConeFit::Compression;
    const DruckerPrager model(p);
    const auto pts = run_element_test(spec_for(ElementPath::DrainedTriaxial, p, 5.0e4, {0.02}, 200));
    const std::size_t i = first_plastic(pts);
    ASSERT_LT(i, pts.size() - 10);
    const double expected = 6.0 * std::sin(psi * kDeg) / (3.0 - std::sin(psi * kDeg));
    int checked = 0;
    for (std::size_t j = i + 1; j < pts.size(); ++j) {
      const Sym6 d_eps_p = (pts[j].strain - pts[j - 1].strain) -
                           elastic_strain(model, pts[j].stress - pts[j - 1].stress);
      const double d_v = trace(d_eps_p);
      const double d_q = (2.0 / 3.0) * (d_eps_p[XX] - d_eps_p[YY]);  // axial shortening: > 0
      ASSERT_GT(d_q, 0.0);
      worst(d_v / d_q - expected);
      ASSERT_NEAR(d_v / d_q, expected, 1e-9) << "psi " << psi << " step " << j;
      // Equivalent plastic strain increment is d lambda = sqrt(3) d eps_q^p here.
      ASSERT_NEAR(pts[j].equivalent_plastic_strain - pts[j - 1].equivalent_plastic_strain,
                  std::sqrt(3.0) * d_q, 1e-9 * d_q);
      ++checked;
    }
    EXPECT_GT(checked, 100);
  }
}

TEST(DruckerPragerFlow, SimpleShearIncrementFollowsPlasticPotential) {
  // Every plastic increment: d eps_v^p / d gamma^p = 3 alpha_g / (sqrt(2) n_xy), n = xi/|xi| at
  // the end of the increment (backward Euler), for non-associated and associated flow.
  Worst worst("simple shear: |d eps_v^p / d gamma^p - 3 alpha_g / (sqrt2 n_xy)| per increment");
  for (double psi : {0.0, 15.0, 40.0}) {
    const DruckerPragerParameters p = sand(40.0, psi, 1.0e3);
    const DruckerPrager model(p);
    const auto pts = run_element_test(spec_for(ElementPath::SimpleShear, p, 1.0e4, {0.05}, 100));
    const std::size_t i = first_plastic(pts);
    ASSERT_LT(i, pts.size() - 10);
    for (std::size_t j = i; j < pts.size(); ++j) {
      const Sym6 d_eps_p = (pts[j].strain - pts[j - 1].strain) -
                           elastic_strain(model, pts[j].stress - pts[j - 1].stress);
      const Sym6 xi = deviator(pts[j].stress) - pts[j].back_stress;
      const double n_xy = xi[XY] / std::sqrt(double_contract(xi, xi));
      const double expected = 3.0 * model.alpha_dilatancy() / (std::sqrt(2.0) * n_xy);
      worst(trace(d_eps_p) / (2.0 * d_eps_p[XY]) - expected);
      ASSERT_NEAR(trace(d_eps_p) / (2.0 * d_eps_p[XY]), expected, 1e-8) << "psi " << psi;
    }
  }
}

TEST(DruckerPragerFlow, SteadySimpleShearDilatesAtTanPsi) {
  // Plane-strain cone: at steady flow d eps_v / d gamma = 3 alpha_g / sqrt(1 - 12 alpha_g^2) = tan psi.
  Worst worst("steady simple shear (gamma = 1.5): |d eps_v / d gamma - tan psi|, psi = 0, 10, 25, 40");
  for (double psi : {0.0, 10.0, 25.0, 40.0}) {
    const auto pts = run_element_test(
        spec_for(ElementPath::SimpleShear, sand(40.0, psi, 10.0), 1.0e4, {1.5}, 1500));
    const auto& a = pts[pts.size() - 2];
    const auto& b = pts.back();
    const double slope = (trace(b.strain) - trace(a.strain)) / (2.0 * (b.strain[XY] - a.strain[XY]));
    worst(slope - std::tan(psi * kDeg));
    EXPECT_NEAR(slope, std::tan(psi * kDeg), 1e-9) << "psi " << psi;
  }
}

// ---- perfect plasticity and hardening -----------------------------------------------------------

TEST(DruckerPragerHardening, PerfectPlasticityStaysOnTheSurface) {
  Worst worst_f("perfect plasticity, triaxial to 20 %: |f| / stress scale");
  Worst worst_s("perfect plasticity: |sigma - sigma_yield| / |sigma_yield|");
  for (double psi : {0.0, 20.0}) {
    const DruckerPragerParameters p = sand(30.0, psi, 5.0e3);
    const DruckerPrager model(p);
    const auto pts = run_element_test(spec_for(ElementPath::DrainedTriaxial, p, 5.0e4, {0.2}, 2000));
    const std::size_t i = first_plastic(pts);
    ASSERT_LT(i, 100u);
    for (std::size_t j = i; j < pts.size(); ++j) {
      ASSERT_NE(pts[j].regime, Regime::Elastic);
      worst_f(pts[j].yield_function / stress_scale(pts[j].stress, model));
      worst_s((pts[j].stress - pts[i].stress).norm() / pts[i].stress.norm());
      ASSERT_LE(std::abs(pts[j].yield_function), 1e-10 * stress_scale(pts[j].stress, model));
      ASSERT_LT((pts[j].stress - pts[i].stress).norm(), 1e-10 * pts[i].stress.norm())
          << "stress must not drift under continued straining, step " << j;
    }
  }
}

TEST(DruckerPragerHardening, SimpleShearSlopeIsGHOverGPlusH) {
  // psi = 0, pure shear: tau = tau_y + H gamma^p and tau = G (gamma - gamma^p) give
  // d tau / d gamma = G H / (G + H) for every mixing (monotonic loading).
  Worst worst("simple shear hardening slope: relative error vs G H / (G + H), m = 0, 0.2, 1");
  for (double m : {0.0, 0.2, 1.0}) {
    const DruckerPragerParameters p = hardening_sand(0.0, 5.0e3, 2.0e6, m);
    const DruckerPrager model(p);
    const auto pts = run_element_test(spec_for(ElementPath::SimpleShear, p, 1.0e4, {0.03}, 300));
    const std::size_t i = first_plastic(pts);
    ASSERT_LT(i, pts.size() - 10);
    const double g = model.shear_modulus(), h = p.hardening_modulus;
    for (std::size_t j = i + 1; j < pts.size(); ++j) {
      const double slope = (pts[j].stress[XY] - pts[j - 1].stress[XY]) /
                           (2.0 * (pts[j].strain[XY] - pts[j - 1].strain[XY]));
      worst(slope / (g * h / (g + h)) - 1.0);
      ASSERT_NEAR(slope, g * h / (g + h), 1e-8 * g * h / (g + h)) << "m " << m << " step " << j;
      ASSERT_LE(std::abs(pts[j].yield_function), 1e-10 * stress_scale(pts[j].stress, model));
    }
  }
}

TEST(DruckerPragerHardening, UniaxialCompressionTangentModulus) {
  // Lateral stress held: E_t = 1 / (1/E + (1/sqrt3 - alpha)(1/sqrt3 - alpha_g) / H).
  Worst worst("uniaxial hardening slope: relative error vs E_t, psi = 0, 15, m = 0, 0.2, 1");
  for (double psi : {0.0, 15.0}) {
    for (double m : {0.0, 0.2, 1.0}) {
      const DruckerPragerParameters p = hardening_sand(psi, 2.0e4, 5.0e6, m);
      const DruckerPrager model(p);
      const auto pts = run_element_test(spec_for(ElementPath::UniaxialCompression, p, 0.0, {0.01}, 200));
      const std::size_t i = first_plastic(pts);
      ASSERT_LT(i, pts.size() - 10);
      const double r3 = 1.0 / std::sqrt(3.0);
      const double et = 1.0 / (1.0 / p.young + (r3 - model.alpha()) * (r3 - model.alpha_dilatancy()) / p.hardening_modulus);
      for (std::size_t j = i + 1; j < pts.size(); ++j) {
        const double slope = (pts[j].stress[YY] - pts[j - 1].stress[YY]) /
                             (pts[j].strain[YY] - pts[j - 1].strain[YY]);
        worst(slope / et - 1.0);
        ASSERT_NEAR(slope, et, 1e-8 * et) << "psi " << psi << " m " << m;
        ASSERT_NEAR(pts[j].stress[XX], 0.0, 1e-10 * std::abs(pts[j].stress[YY]));
      }
    }
  }
}

TEST(DruckerPragerHardening, ReverseYieldFollowsPragerMixing) {
  // Shear forward to tau1 (psi = 0), then the reverse yield stress is
  // tau_rev = tau1 - 2 (tau0 + (1 - m)(tau1 - tau0)): isotropic -tau1, kinematic tau1 - 2 tau0.
  const double p0 = 1.0e4;
  Worst worst("reverse yield: |f(tau_rev)| / p0, m = 0, 0.2, 0.5, 1");
  for (double m : {0.0, 0.2, 0.5, 1.0}) {
    const DruckerPragerParameters p = hardening_sand(0.0, 5.0e3, 3.0e6, m);
    const DruckerPrager model(p);
    Sym6 stress = -p0 * identity6();
    DruckerPragerState state;
    Sym6 d_eps = Sym6::Zero();
    d_eps[XY] = 1.0e-4;
    for (int i = 0; i < 100; ++i) model.update(stress, state, d_eps);
    const double tau0 = model.initial_strength() + 3.0 * model.alpha() * p0;
    const double tau1 = stress[XY];
    ASSERT_GT(tau1, tau0 * 1.5);
    const double tau_rev = tau1 - 2.0 * (tau0 + (1.0 - m) * (tau1 - tau0));
    Sym6 probe = stress;
    probe[XY] = tau_rev;
    worst(model.yield_function(probe, state) / p0);
    EXPECT_NEAR(model.yield_function(probe, state), 0.0, 1e-10 * p0) << "m " << m;
    // Unloading elastically to just above tau_rev stays elastic; just below it yields.
    for (double overshoot : {-1e-6, 1e-6}) {
      Sym6 s = stress;
      DruckerPragerState st = state;
      Sym6 back = Sym6::Zero();
      back[XY] = (tau_rev - tau1 - overshoot * tau0) / (2.0 * model.shear_modulus());
      const auto r = model.update(s, st, back);
      EXPECT_EQ(r.regime, overshoot < 0 ? Regime::Elastic : Regime::Cone) << "m " << m;
    }
  }
}

// ---- apex and tension cut-off -------------------------------------------------------------------

TEST(DruckerPragerApex, HydrostaticTensionReturnsToTheApex) {
  for (double c : {0.0, 5.0e3}) {
    for (double psi : {0.0, 30.0}) {
      const DruckerPrager model(sand(30.0, psi, c));
      Sym6 stress = -1.0e4 * identity6();
      DruckerPragerState state;
      const Sym6 d_eps = 1.0e-2 * identity6();  // strong volumetric extension
      const auto r = model.update(stress, state, d_eps);
      EXPECT_EQ(r.regime, Regime::Apex);
      const double apex_mean = model.initial_strength() / (3.0 * model.alpha());
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(stress[i], apex_mean, 1e-12 * (apex_mean + 1.0));
      for (int i = 3; i < 6; ++i) EXPECT_EQ(stress[i], 0.0);
      EXPECT_NEAR(model.yield_function(stress, state), 0.0, 1e-12 * (apex_mean + 1.0));
      EXPECT_NEAR(state.equivalent_plastic_strain, 0.0, 1e-15);  // no deviatoric plastic strain
      EXPECT_GE(r.plastic_work, 0.0);
    }
  }
}

TEST(DruckerPragerApex, ShearedTensionWithHardeningReturnsToTheMovedApex) {
  // Trial beyond the apex normal: xi -> 0, d eps_p = q_tr/(G + H_kin), I1 = k_{n+1}/alpha,
  // beta += H_kin xi_tr/(G + H_kin).
  const DruckerPragerParameters p = hardening_sand(10.0, 5.0e3, 4.0e6, 0.3);
  const DruckerPrager model(p);
  Sym6 stress = Sym6::Zero();
  DruckerPragerState state;
  state.back_stress << 100.0, -50.0, -50.0, 10.0, 0.0, 20.0;
  Sym6 d_eps = 2.0e-3 * identity6();
  d_eps[XY] = 1.0e-5;
  Sym6 trial = stress + 2.0 * model.shear_modulus() * d_eps + model.lame_lambda() * trace(d_eps) * identity6();
  const Sym6 xi = deviator(trial) - state.back_stress;
  const double q = std::sqrt(0.5 * double_contract(xi, xi));
  const double h_kin = 0.3 * p.hardening_modulus, h_iso = 0.7 * p.hardening_modulus;
  const double g = model.shear_modulus();
  const Sym6 beta_expected = state.back_stress + h_kin / (g + h_kin) * xi;
  const double k_expected = model.initial_strength() + h_iso * q / (g + h_kin);
  const auto r = model.update(stress, state, d_eps);
  ASSERT_EQ(r.regime, Regime::Apex);
  EXPECT_NEAR(state.equivalent_plastic_strain, q / (g + h_kin), 1e-15);
  EXPECT_LT((state.back_stress - beta_expected).norm(), 1e-10 * beta_expected.norm());
  EXPECT_NEAR(trace(stress), k_expected / model.alpha(), 1e-12 * k_expected / model.alpha());
  EXPECT_LT((deviator(stress) - state.back_stress).norm(), 1e-10 * stress.norm());
  EXPECT_NEAR(model.yield_function(stress, state), 0.0, 1e-10 * stress.norm());
}

TEST(DruckerPragerApex, TensionCutoffCapsTheMeanStress) {
  DruckerPragerParameters p = sand(30.0, 0.0, 2.0e4);
  p.tension_cutoff = 1.0e3;  // below the apex mean stress k/(3 alpha)
  const DruckerPrager model(p);
  ASSERT_LT(3.0 * p.tension_cutoff, model.initial_strength() / model.alpha());
  // Hydrostatic tension: onto the cap, deviator unchanged (zero).
  {
    Sym6 stress = Sym6::Zero();
    DruckerPragerState state;
    const auto r = model.update(stress, state, 1.0e-3 * identity6());
    EXPECT_EQ(r.regime, Regime::TensionCutoff);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(stress[i], p.tension_cutoff, 1e-12 * p.tension_cutoff);
    EXPECT_NEAR(r.plastic_work,
                p.tension_cutoff * (3.0e-3 - 3.0 * p.tension_cutoff / (3.0 * model.bulk_modulus())),
                1e-12 * r.plastic_work);
  }
  // Tension with a small shear: cap only, the deviator is kept.
  {
    Sym6 stress = Sym6::Zero();
    stress[XY] = 1.0e3;
    DruckerPragerState state;
    const auto r = model.update(stress, state, 1.0e-3 * identity6());
    EXPECT_EQ(r.regime, Regime::TensionCutoff);
    EXPECT_NEAR(trace(stress), 3.0 * p.tension_cutoff, 1e-12 * p.tension_cutoff);
    EXPECT_DOUBLE_EQ(stress[XY], 1.0e3);
    EXPECT_LT(model.yield_function(stress, state), 0.0);
  }
  // Tension with a large shear: the corner, on both the cap and the cone.
  {
    Sym6 stress = Sym6::Zero();
    stress[XY] = 2.0e4;
    DruckerPragerState state;
    const auto r = model.update(stress, state, 1.0e-3 * identity6());
    EXPECT_EQ(r.regime, Regime::TensionCutoff);
    EXPECT_NEAR(trace(stress), 3.0 * p.tension_cutoff, 1e-12 * p.tension_cutoff);
    EXPECT_NEAR(model.yield_function(stress, state), 0.0, 1e-10 * stress.norm());
    EXPECT_GT(state.equivalent_plastic_strain, 0.0);
  }
  // A cut-off above the apex never acts: the apex limits.
  DruckerPragerParameters high = p;
  high.tension_cutoff = 1.0e9;
  const DruckerPrager model_high(high);
  Sym6 stress = Sym6::Zero();
  DruckerPragerState state;
  EXPECT_EQ(model_high.update(stress, state, 1.0e-2 * identity6()).regime, Regime::Apex);
  EXPECT_NEAR(trace(stress), model_high.initial_strength() / model_high.alpha(), 1e-9);
}

// ---- the return mapping on random states --------------------------------------------------------

TEST(DruckerPragerReturn, RandomStatesAreConsistent) {
  // For random stresses, back stresses and strain increments in every regime:
  //  - admissible: f <= tol and I1 <= 3 p_t after the update; |f| <= 1e-10 scale when plastic;
  //  - plastic strain d_eps - C^-1 d_sigma follows the flow rule on the cone (backward Euler);
  //  - reported plastic work equals sigma_{n+1} : d_eps^p, and is >= 0 without kinematic hardening.
  std::mt19937 rng(12345);
  int count[4] = {0, 0, 0, 0};
  Worst worst_f("random states: |f| / stress scale after a plastic return");
  Worst worst_flow("random states: |d eps^p - d lambda dg/dsigma| / |d eps| on the cone");
  Worst worst_work("random states: |W_p - sigma:d eps^p| / (scale |d eps^p|)");
  for (int trial = 0; trial < 20000; ++trial) {
    DruckerPragerParameters p = sand(20.0 + 25.0 * (trial % 5) / 4.0, 0.0, 1.0e3 * (trial % 3));
    p.dilatancy_angle_deg = p.friction_angle_deg * ((trial / 5) % 3) / 2.0;
    p.hardening_modulus = (trial % 7 < 3) ? 0.0 : 5.0e6;
    p.kinematic_fraction = (trial % 11 < 5) ? 0.0 : 0.6;
    if (trial % 13 == 0) p.tension_cutoff = 200.0;
    p.cone = static_cast<ConeFit>(trial % 4);
    const DruckerPrager model(p);
    DruckerPragerState state;
    state.equivalent_plastic_strain = 0.01 * (trial % 2);
    if (p.kinematic_fraction > 0.0 && p.hardening_modulus > 0.0)
      state.back_stress = deviator(random_sym6(rng, 2.0e3));
    Sym6 stress = -1.0e4 * identity6() + random_sym6(rng, 3.0e3);
    const Sym6 d_eps = random_sym6(rng, 2.0e-3);
    const Sym6 stress0 = stress;
    const DruckerPragerState state0 = state;
    const auto r = model.update(stress, state, d_eps);
    ++count[static_cast<int>(r.regime)];
    const double scale = stress_scale(stress, model) + stress_scale(stress0, model);
    const double f = model.yield_function(stress, state);
    ASSERT_LE(f, 1e-10 * scale);
    ASSERT_LE(trace(stress), 3.0 * p.tension_cutoff + 1e-10 * scale);
    const Sym6 d_eps_p = d_eps - elastic_strain(model, stress - stress0);
    if (r.regime == Regime::Elastic) {
      ASSERT_LT(d_eps_p.norm(), 1e-12);
      ASSERT_EQ(r.plastic_work, 0.0);
      continue;
    }
    if (r.regime != Regime::TensionCutoff || state.equivalent_plastic_strain > state0.equivalent_plastic_strain) {
      worst_f(f / scale);
      ASSERT_LE(std::abs(f), 1e-10 * scale) << "regime " << regime_name(r.regime);
    }
    worst_work((r.plastic_work - double_contract(stress, d_eps_p)) / (scale * d_eps_p.norm()));
    ASSERT_NEAR(r.plastic_work, double_contract(stress, d_eps_p), 1e-9 * scale * d_eps_p.norm());
    if (state0.back_stress.isZero(0.0)) {
      ASSERT_GE(r.plastic_work, 0.0) << regime_name(r.regime) << " trial " << trial;
    }
    const double dl = state.equivalent_plastic_strain - state0.equivalent_plastic_strain;
    const Sym6 de_p = deviator(d_eps_p);
    ASSERT_NEAR(std::sqrt(2.0 * double_contract(de_p, de_p)), dl, 1e-9 * (dl + d_eps.norm()));
    // Prager: d beta = 2 H_kin de^p.
    const double h_kin = p.kinematic_fraction * p.hardening_modulus;
    ASSERT_LT((state.back_stress - state0.back_stress - 2.0 * h_kin * de_p).norm(), 1e-9 * scale);
    if (r.regime == Regime::Cone) {
      const Sym6 xi = deviator(stress) - state.back_stress;
      Sym6 flow = xi / (std::sqrt(2.0) * std::sqrt(double_contract(xi, xi)));
      flow += model.alpha_dilatancy() * identity6();
      worst_flow((d_eps_p - dl * flow).norm() / d_eps.norm());
      ASSERT_LT((d_eps_p - dl * flow).norm(), 1e-9 * d_eps.norm());
    }
  }
  std::printf("[ measured ] random states per regime: elastic %d, cone %d, apex %d, cut-off %d\n",
              count[0], count[1], count[2], count[3]);
  for (int i = 0; i < 4; ++i) EXPECT_GT(count[i], 100) << "regime " << i << " under-sampled";
}

// ---- objectivity --------------------------------------------------------------------------------

TEST(DruckerPragerObjectivity, UpdateCommutesWithRigidRotation) {
  // Rotating the stressed point (stress, back stress) and the strain increment by any rotation Q
  // gives the rotated result: invariants, eps_p, regime and plastic work agree to round-off.
  std::mt19937 rng(777);
  DruckerPragerParameters p = sand(35.0, 10.0, 2.0e3);
  p.hardening_modulus = 3.0e6;
  p.kinematic_fraction = 0.5;
  p.tension_cutoff = 500.0;
  const DruckerPrager model(p);
  Worst worst("rigid rotation Q: |Q update(sigma) Q^T - update(Q sigma Q^T)| / |sigma|");
  for (int trial = 0; trial < 2000; ++trial) {
    const Mat3 q = random_rotation(rng);
    DruckerPragerState a;
    a.equivalent_plastic_strain = 0.002;
    a.back_stress = deviator(random_sym6(rng, 1.0e3));
    Sym6 sa = -1.0e4 * identity6() + random_sym6(rng, 4.0e3);
    const Sym6 da = random_sym6(rng, 2.0e-3);
    DruckerPragerState b = a;
    b.back_stress = rotate(q, a.back_stress);
    Sym6 sb = rotate(q, sa);
    const auto ra = model.update(sa, a, da);
    const auto rb = model.update(sb, b, rotate(q, da));
    const double scale = sa.norm() + 1.0e4;
    ASSERT_EQ(ra.regime, rb.regime);
    worst((rotate(q, sa) - sb).norm() / scale);
    ASSERT_LT((rotate(q, sa) - sb).norm(), 1e-12 * scale);
    ASSERT_LT((rotate(q, a.back_stress) - b.back_stress).norm(), 1e-12 * scale);
    ASSERT_NEAR(trace(sa), trace(sb), 1e-12 * scale);
    ASSERT_NEAR(j2(sa), j2(sb), 1e-12 * scale * scale);
    ASSERT_NEAR(to_matrix(sa).determinant(), to_matrix(sb).determinant(), 1e-12 * scale * scale * scale);
    ASSERT_NEAR(a.equivalent_plastic_strain, b.equivalent_plastic_strain, 1e-15);
    ASSERT_NEAR(ra.plastic_work, rb.plastic_work, 1e-12 * scale * da.norm());
  }
}

TEST(DruckerPragerObjectivity, SpinKeepsInvariantsToRoundOff) {
  // A stressed point on a hardened, shifted surface spun a quarter turn about z in N steps
  // (rotate_objectively on the stress, rotate_state on the back stress, update with zero strain):
  // the invariants of sigma and beta are kept to round-off, the point stays on the surface with
  // no spurious plastic flow, and the result converges to the exact rotation Q sigma Q^T at
  // second order in 1/N (the Hughes–Winget angle per step is 2 atan(w/2) = w - w^3/12 + ...).
  const DruckerPragerParameters p = hardening_sand(10.0, 2.0e3, 2.0e6, 0.5);
  const DruckerPrager model(p);
  Sym6 stress0 = -1.0e4 * identity6();
  DruckerPragerState state0;
  Sym6 d = Sym6::Zero();
  d[XX] = -2.0e-4;
  d[XY] = 3.0e-4;
  d[YZ] = -1.0e-4;
  for (int i = 0; i < 20; ++i) model.update(stress0, state0, d);  // plastic, on the surface
  ASSERT_NEAR(model.yield_function(stress0, state0), 0.0, 1e-10 * stress0.norm());
  ASSERT_GT(state0.back_stress.norm(), 0.0);
  const double angle = kPi / 2.0;
  Mat3 q = Mat3::Identity();
  q(0, 0) = std::cos(angle);
  q(0, 1) = -std::sin(angle);
  q(1, 0) = std::sin(angle);
  q(1, 1) = std::cos(angle);
  const double scale = stress0.norm();
  const double det0 = to_matrix(stress0).determinant();
  double previous_error = 0.0;
  for (int n : {1000, 4000}) {
    Sym6 stress = stress0;
    DruckerPragerState state = state0;
    const double w = angle / n;  // W_xy = -w: counter-clockwise about z, R = I + dW + ...
    for (int i = 0; i < n; ++i) {
      rotate_objectively(stress, 0.0, 0.0, -w);
      model.rotate_state(state, 0.0, 0.0, -w);
      model.update(stress, state, Sym6::Zero());
    }
    std::printf("[ measured ] quarter turn in %d spin steps: |dI1|/|s| = %.1e, |dJ2|/|s|^2 = %.1e, "
                "|dJ3|/|s|^3 = %.1e, |f|/|s| = %.1e, |sigma - Q sigma0 Q^T|/|s| = %.1e\n",
                n, std::abs(trace(stress) - trace(stress0)) / scale,
                std::abs(j2(stress) - j2(stress0)) / (scale * scale),
                std::abs(to_matrix(stress).determinant() - det0) / (scale * scale * scale),
                std::abs(model.yield_function(stress, state)) / scale,
                (stress - rotate(q, stress0)).norm() / scale);
    const double roundoff = n * 1e-15;  // a few ulps per step
    EXPECT_NEAR(trace(stress), trace(stress0), roundoff * scale);
    EXPECT_NEAR(j2(stress), j2(stress0), roundoff * scale * scale);
    EXPECT_NEAR(to_matrix(stress).determinant(), det0, roundoff * scale * scale * scale);
    EXPECT_NEAR(j2(state.back_stress), j2(state0.back_stress), roundoff * scale * scale);
    EXPECT_NEAR(trace(state.back_stress), 0.0, roundoff * scale);
    EXPECT_NEAR(state.equivalent_plastic_strain, state0.equivalent_plastic_strain,
                1e-12 * state0.equivalent_plastic_strain);
    EXPECT_LE(std::abs(model.yield_function(stress, state)), 1e-10 * scale);
    const double error = (stress - rotate(q, stress0)).norm() / scale;
    if (n == 4000) {
      EXPECT_NEAR(previous_error / error, 16.0, 0.5);  // second order in 1/N
    }
    previous_error = error;
    EXPECT_LT((state.back_stress - rotate(q, state0.back_stress)).norm(), 2.0 * error * scale);
  }
}

TEST(DruckerPragerObjectivity, HughesWingetAgreesWithJaumannToFirstOrder) {
  // rotate_objectively and core's jaumann_rotate differ by O(|dW|^2) only.
  std::mt19937 rng(3);
  for (double w : {1e-2, 1e-3}) {
    const Sym6 s0 = random_sym6(rng, 1.0e4);
    Sym6 a = s0, b = s0;
    rotate_objectively(a, 0.7 * w, -0.4 * w, w);
    jaumann_rotate(b, 0.7 * w, -0.4 * w, w);
    EXPECT_LT((a - b).norm(), 4.0 * w * w * s0.norm());
    EXPECT_GT((a - s0).norm(), 0.1 * w * s0.norm());  // it does rotate
  }
}

TEST(DruckerPragerObjectivity, WrittenOutRotationEqualsTheMatrixProduct) {
  // rotate_objectively is R S R^T written out; compare with the matrix product it replaces, for
  // small and large spins (R = I + 2 (A + A^2) / (1 + |a|^2), A = dW / 2).
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double w : {1e-6, 1e-2, 0.5, 3.0}) {
    const Sym6 s0 = random_sym6(rng, 1.0e4);
    const double wyz = w * u(rng), wxz = w * u(rng), wxy = w * u(rng);
    Mat3 a;
    a << 0.0, 0.5 * wxy, 0.5 * wxz, -0.5 * wxy, 0.0, 0.5 * wyz, -0.5 * wxz, -0.5 * wyz, 0.0;
    const double n2 = 0.25 * (wxy * wxy + wxz * wxz + wyz * wyz);
    const Mat3 r = Mat3::Identity() + (2.0 / (1.0 + n2)) * (a + a * a);
    const Sym6 expected = from_matrix(r * to_matrix(s0) * r.transpose());
    Sym6 got = s0;
    rotate_objectively(got, wyz, wxz, wxy);
    EXPECT_LT((got - expected).norm(), 1e-12 * s0.norm()) << w;
  }
}

// ---- helpers for the MPM loop -------------------------------------------------------------------

TEST(DruckerPragerHelpers, WithDilatancyAndReset) {
  DruckerPragerParameters p = sand(40.0, 12.0, 10.0);
  const DruckerPrager model(p);
  const DruckerPrager flowing = model.with_dilatancy(0.0);
  EXPECT_GT(model.alpha_dilatancy(), 0.0);
  EXPECT_EQ(flowing.alpha_dilatancy(), 0.0);
  EXPECT_EQ(flowing.alpha(), model.alpha());
  EXPECT_EQ(flowing.initial_strength(), model.initial_strength());
  EXPECT_THROW(model.with_dilatancy(41.0), Error);
  DruckerPragerState state;
  state.equivalent_plastic_strain = 0.3;
  state.back_stress.setConstant(7.0);
  state.reset();
  EXPECT_EQ(state.equivalent_plastic_strain, 0.0);
  EXPECT_EQ(state.back_stress, Sym6::Zero());
}

}  // namespace
}  // namespace drucker_prager_test
}  // namespace talus
