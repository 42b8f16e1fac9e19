// VTU and CalculiX writers (parsed back), and the force calibration search.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>

#include "pectus/errors.h"
#include "pectus/fe/calibrate.h"
#include "pectus/fe/io.h"
#include "pectus/fe/solver.h"

using namespace pectus::fe;
using Eigen::Vector3d;

namespace {
std::string slurp(const std::string& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}
std::string tmp(const std::string& name) { return ::testing::TempDir() + name; }

// two-tissue bar: lower half bone (1), upper half cartilage (2), clamped at z = 0, tip force along y
struct Bar {
  TetMesh m;
  Problem p;
  int tip = -1;
  Bar(int order, double F) {
    m = structuredBox(10, 10, 60, 2, 2, 12, 1);
    for (int t = 0; t < m.numTets(); ++t)
      if ((m.nodes[m.tets[t][0]] + m.nodes[m.tets[t][1]] + m.nodes[m.tets[t][2]] + m.nodes[m.tets[t][3]]).z() / 4 > 30) m.tissue[t] = 2;
    if (order == 2) m = toQuadratic(m);
    p.mesh = &m;
    p.materials = {{1, {11500.0, 0.3}}, {2, {100.0, 0.4}}};
    for (int i = 0; i < m.numNodes(); ++i) {
      if (m.nodes[i].z() < 1e-9) p.fixNode(i);
      if ((m.nodes[i] - Vector3d(5, 5, 60)).norm() < 1e-9) tip = i;
    }
    p.addForce(tip, Vector3d(0, F, 0));
  }
};
}  // namespace

TEST(FeIo, VtuRoundTrip) {
  for (int order : {1, 2}) {
    Bar b(order, 1.0);
    const Result r = solveLinear(b.p);
    const std::string path = tmp("fe_bar.vtu");
    writeVtu(path, b.m, &r);
    const std::string s = slurp(path);
    std::smatch mt;
    ASSERT_TRUE(std::regex_search(s, mt, std::regex("NumberOfPoints=\"(\\d+)\" NumberOfCells=\"(\\d+)\"")));
    EXPECT_EQ(std::stoi(mt[1]), b.m.numNodes());
    EXPECT_EQ(std::stoi(mt[2]), b.m.numTets());
    for (const char* name : {"\"tissue\"", "\"displacement\"", "\"von_mises\"", "\"equivalent_strain\"", "\"connectivity\""})
      EXPECT_NE(s.find(name), std::string::npos) << name;
    // parse the displacement array back and compare the tip node
    const size_t at = s.find("Name=\"displacement\"");
    std::istringstream in(s.substr(s.find('\n', at) + 1));
    Vector3d u;
    for (int i = 0; i <= b.tip; ++i) in >> u.x() >> u.y() >> u.z();
    EXPECT_NEAR((u - r.displacement(b.tip)).norm(), 0.0, 1e-9 * r.displacement(b.tip).norm());
    // cell types
    const size_t ty = s.find("Name=\"types\"");
    std::istringstream ti(s.substr(s.find('\n', ty) + 1));
    int type = 0;
    ti >> type;
    EXPECT_EQ(type, order == 2 ? 24 : 10);
  }
  EXPECT_THROW(writeVtu("/nonexistent-dir/x.vtu", structuredBox(1, 1, 1, 1, 1, 1)), pectus::InputError);
}

TEST(FeIo, CalculixDeck) {
  Bar b(2, 3.0);
  InpOptions o;
  o.nlgeom = true;
  o.increments = 8;
  o.printNodes = {b.tip};
  const std::string path = tmp("fe_bar.inp");
  writeCalculixInp(path, b.p, o);
  const std::string s = slurp(path);
  auto count = [&](const std::string& what) {
    size_t c = 0;
    for (size_t pos = s.find(what); pos != std::string::npos; pos = s.find(what, pos + 1)) ++c;
    return c;
  };
  EXPECT_EQ(count("*ELEMENT, TYPE=C3D10"), 2u);
  EXPECT_EQ(count("*MATERIAL, NAME="), 2u);
  EXPECT_NE(s.find("*MATERIAL, NAME=CARTILAGE\n*ELASTIC\n100, 0.4"), std::string::npos);
  EXPECT_NE(s.find("*STEP, NLGEOM"), std::string::npos);
  EXPECT_NE(s.find("*STATIC, DIRECT\n0.125, 1.0"), std::string::npos);
  EXPECT_NE(s.find("*CLOAD\n" + std::to_string(b.tip + 1) + ", 2, 3\n"), std::string::npos);
  // one line per element, 11 entries each
  const size_t e0 = s.find("*ELEMENT");
  std::istringstream in(s.substr(s.find('\n', e0) + 1));
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(std::count(line.begin(), line.end(), ','), 10);
  // every fixed dof is in *BOUNDARY
  const size_t bStart = s.find("*BOUNDARY\n") + 10, bEnd = s.find("*STEP");
  EXPECT_EQ(static_cast<size_t>(std::count(s.begin() + bStart, s.begin() + bEnd, '\n')), b.p.fixed.size());
  o.nlgeom = false;
  writeCalculixInp(path, b.p, o);
  EXPECT_EQ(slurp(path).find("NLGEOM"), std::string::npos);
}

// a deck written by writeCalculixInp reads back as the same model: nodes, tets and their tissues,
// materials, fixed dofs, forces, print nodes, NLGEOM increments; written again it is the same text,
// and both models solve to the same displacements
TEST(FeIo, CalculixDeckReadsBackAsTheSameModel) {
  for (int order : {1, 2}) {
    Bar b(order, 3.0);
    b.p.fixed.push_back({b.tip, 0, 0.25});  // a prescribed non-zero displacement too
    InpOptions o;
    o.nlgeom = order == 2;
    o.increments = 8;
    o.printNodes = {b.tip, 0};
    const std::string path = tmp("fe_roundtrip.inp"), again = tmp("fe_roundtrip2.inp");
    writeCalculixInp(path, b.p, o);
    const auto r = readCalculixInp(path);
    ASSERT_EQ(r->problem.mesh, &r->mesh);
    EXPECT_EQ(r->mesh.order, b.m.order);
    ASSERT_EQ(r->mesh.numNodes(), b.m.numNodes());
    ASSERT_EQ(r->mesh.numTets(), b.m.numTets());
    double dx = 0;
    for (int i = 0; i < b.m.numNodes(); ++i) dx = std::max(dx, (r->mesh.nodes[i] - b.m.nodes[i]).norm());
    EXPECT_LT(dx, 1e-9);
    EXPECT_EQ(r->mesh.tets, b.m.tets);
    EXPECT_EQ(r->mesh.tissue, b.m.tissue);
    ASSERT_EQ(r->problem.materials.size(), 2u);
    EXPECT_EQ(r->problem.materials.at(2).E, 100.0);
    EXPECT_EQ(r->problem.materials.at(2).nu, 0.4);
    ASSERT_EQ(r->problem.fixed.size(), b.p.fixed.size());
    EXPECT_EQ(r->problem.fixed.back().node, b.tip);
    EXPECT_EQ(r->problem.fixed.back().value, 0.25);
    EXPECT_EQ(r->problem.force[std::size_t(b.tip)], Vector3d(0, 3, 0));
    EXPECT_EQ(r->options.printNodes, o.printNodes);
    EXPECT_EQ(r->options.nlgeom, o.nlgeom);
    if (o.nlgeom) EXPECT_EQ(r->options.increments, 8);
    writeCalculixInp(again, r->problem, r->options);
    EXPECT_EQ(slurp(again), slurp(path));
    const Eigen::VectorXd u0 = solveLinear(b.p).u, u1 = solveLinear(r->problem).u;
    EXPECT_LT((u0 - u1).norm(), 1e-9 * u0.norm());
  }
}

// a neo-Hookean tissue goes to an NLGEOM deck as *HYPERELASTIC, NEO HOOKE (C10 = mu / 2, D1 = 2 / K) and
// reads back as CalculiX's form with the same E and nu; a small-strain deck keeps *ELASTIC (Hooke's law,
// what both programs solve there)
TEST(FeIo, NeoHookeanTissueIsCalculixNeoHooke) {
  Bar b(2, 3.0);
  b.p.materials.at(2).model = MaterialModel::NeoHookeanDecoupled;
  InpOptions o;
  o.nlgeom = true;
  o.increments = 4;
  const std::string path = tmp("fe_neo.inp"), again = tmp("fe_neo2.inp");
  writeCalculixInp(path, b.p, o);
  const std::string text = slurp(path);
  const double mu = 100.0 / (2 * 1.4), K = 100.0 / (3 * 0.2);
  const std::size_t at = text.find("*HYPERELASTIC, NEO HOOKE\n");
  ASSERT_NE(at, std::string::npos);
  double c10 = 0, d1 = 0;
  ASSERT_EQ(std::sscanf(text.c_str() + at + 25, "%lf, %lf", &c10, &d1), 2);
  EXPECT_NEAR(c10 / (mu / 2), 1.0, 1e-11);
  EXPECT_NEAR(d1 / (2 / K), 1.0, 1e-11);
  EXPECT_NE(text.find("*ELASTIC\n11500, 0.3"), std::string::npos);  // the bone stays St Venant-Kirchhoff
  const auto r = readCalculixInp(path);
  const Material& m2 = r->problem.materials.at(2);
  EXPECT_EQ(m2.model, MaterialModel::NeoHookeanDecoupled);
  EXPECT_NEAR(m2.E, 100.0, 1e-9);
  EXPECT_NEAR(m2.nu, 0.4, 1e-12);
  EXPECT_EQ(r->problem.materials.at(1).model, MaterialModel::StVenantKirchhoff);
  writeCalculixInp(again, r->problem, r->options);
  EXPECT_EQ(slurp(again), text);
  NewtonOptions no;
  no.loadSteps = 4;
  const Eigen::VectorXd u0 = solveNonlinear(b.p, no).u, u1 = solveNonlinear(r->problem, no).u;
  EXPECT_LT((u0 - u1).norm(), 1e-8 * u0.norm());
  // the ln J form is written as the nearest ccx form, with a comment saying so
  b.p.materials.at(2).model = MaterialModel::NeoHookean;
  writeCalculixInp(path, b.p, o);
  EXPECT_NE(slurp(path).find("other volumetric term"), std::string::npos);
  EXPECT_EQ(readCalculixInp(path)->problem.materials.at(2).model, MaterialModel::NeoHookeanDecoupled);
  o.nlgeom = false;
  writeCalculixInp(path, b.p, o);
  EXPECT_EQ(slurp(path).find("HYPERELASTIC"), std::string::npos);
  EXPECT_NE(slurp(path).find("*ELASTIC\n100, 0.4"), std::string::npos);
}

TEST(FeIo, CalculixDeckErrorsNameTheLine) {
  Bar b(1, 1.0);
  const std::string path = tmp("fe_bad.inp");
  writeCalculixInp(path, b.p);
  const std::string good = slurp(path);
  auto expectError = [&](const std::string& deck, const std::string& what) {
    std::ofstream(path) << deck;
    try {
      readCalculixInp(path);
      ADD_FAILURE() << "no error for " << what;
    } catch (const pectus::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  std::string s = good;
  s.replace(s.find("C3D4"), 4, "C3D8");
  expectError(s, "only *ELEMENT, TYPE=C3D4 or C3D10");
  s = good;
  s.insert(s.find("*BOUNDARY"), "*AMPLITUDE, NAME=A\n");
  expectError(s, "keyword *AMPLITUDE is not read");
  s = good;
  s.replace(s.find("\n1, ") + 1, 3, "1, x");  // node 1's x coordinate
  expectError(s, "line 5: 'x");
  s = good;
  const size_t e = s.find('\n', s.find("*ELEMENT")) + 1;
  const size_t n0 = s.find(',', e) + 2;  // the first element's first node becomes one that is not defined
  s.replace(n0, s.find(',', n0) - n0, "888888");
  expectError(s, "node 888888 is used but not defined");
  expectError("*NODE\n1, 0, 0, 0\n", "no *ELEMENT");
  EXPECT_THROW(readCalculixInp("/nonexistent-dir/x.inp"), pectus::InputError);
}

TEST(FeCalibrate, AnalyticSofteningCurve) {
  auto d = [](double F) { return 60.0 * (1.0 - std::exp(-F / 90.0)); };
  CalibrationOptions o;
  o.initialForce = 20;
  for (double target : {34.0, 40.0, 44.7}) {
    const CalibrationResult r = calibrateForce(d, target, o);
    EXPECT_LE(std::abs(d(r.force) - target), 0.1) << target;
    EXPECT_LE(r.evaluations, 8) << target;
    EXPECT_NEAR(r.force, -90.0 * std::log(1 - target / 60.0), 0.1 / (60.0 / 90.0 * std::exp(-r.force / 90)) * 1.01);
  }
  o.maxForce = 1000;
  try {
    calibrateForce(d, 70.0, o);
    FAIL() << "unreachable target accepted";
  } catch (const pectus::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("No force up to"), std::string::npos) << e.what();
  }
  EXPECT_THROW(calibrateForce([](double F) { return -F; }, 10.0, o), pectus::InputError);
}

TEST(FeCalibrate, NonlinearBarTipElevation) {
  // find the tip force lifting the two-tissue bar's tip by 20 mm (nonlinear, TET4), start from the linear compliance
  Bar b(1, 1.0);
  Solver s(b.p);
  const double compliance = s.solveLinear().displacement(b.tip).y();
  ASSERT_GT(compliance, 0);
  NewtonOptions no;
  no.loadSteps = 4;
  int solves = 0;
  auto d = [&](double F) {
    ++solves;
    return s.solveNonlinear(no, F).displacement(b.tip).y();
  };
  const double target = 20.0;
  CalibrationOptions o;
  o.initialForce = target / compliance;
  const CalibrationResult r = calibrateForce(d, target, o);
  std::printf("[calibrate] force %.4f N -> %.4f mm in %d nonlinear solves (linear guess %.4f N)\n", r.force, r.displacement,
              r.evaluations, o.initialForce);
  for (const auto& [f, dd] : r.history) std::printf("  %.4f N -> %.4f mm\n", f, dd);
  EXPECT_LE(std::abs(s.solveNonlinear(no, r.force).displacement(b.tip).y() - target), 0.1);
  EXPECT_LE(r.evaluations, 4);
  EXPECT_EQ(solves, r.evaluations);
}

// A stiffening force-displacement curve observed at every load increment (as the nonlinear solves report
// it): the calibration brackets from the increments and lands within tolerance in at most 4 solves, where
// the plain secant through the evaluations needs more.
TEST(Calibration, IncrementObservationsCutTheSolves) {
  auto curve = [](double F) { return 60.0 * (1.0 - std::exp(-F / 12.0)); };
  CalibrationOptions o;
  o.initialForce = 44.7 / 5.0;  // linear compliance 5 mm/N, as on the cage
  o.tolerance = 0.1;
  const auto withObs = calibrateForce(
      [&](double F, const Observer& obs) {
        const int n = std::max(5, int(std::ceil(F / 20.0)));
        for (int k = 1; k <= n; ++k) obs(F * k / n, curve(F * k / n));
        return curve(F);
      },
      44.7, o);
  const auto plain = calibrateForce([&](double F) { return curve(F); }, 44.7, o);
  EXPECT_NEAR(curve(withObs.force), 44.7, 0.1);
  EXPECT_LE(withObs.evaluations, 4);  // the target: calibration in <= 4 nonlinear solves
  EXPECT_LT(withObs.evaluations, plain.evaluations);
}

// Curves shaped like the default cage's (TET10, large displacement: linear compliance 5.5 mm/N, 44.7 mm
// at 26.3 N, i.e. strongly stiffening), observed at every load increment as the nonlinear solves report
// them (max(5, F/20 N) increments): interpolating on every state seen calibrates in at most 4 solves (3 for
// the lower targets).
TEST(Calibration, CageShapedCurvesInFourSolves) {
  const std::vector<std::pair<const char*, std::function<double(double)>>> curves{
      {"exponential", [](double F) { return 46.9 * (1.0 - std::exp(-F / 8.52)); }},
      {"rational", [](double F) { return 5.5 * F / (1.0 + 0.0928 * F); }}};
  for (const auto& [name, curve] : curves)
    for (double target : {34.0, 40.0, 44.7}) {
      CalibrationOptions o;
      o.initialForce = target / 5.5;
      o.tolerance = 0.1;
      const auto r = calibrateForce(
          [&](double F, const Observer& obs) {
            const int n = std::max(5, int(std::ceil(F / 20.0)));
            for (int k = 1; k <= n; ++k) obs(F * k / n, curve(F * k / n));
            return curve(F);
          },
          target, o);
      std::printf("[calibrate %s] %.1f mm: %.3f N in %d solves:", name, target, r.force, r.evaluations);
      for (const auto& [f, d] : r.history) std::printf(" %.2f N -> %.2f mm", f, d);
      std::printf("\n");
      EXPECT_NEAR(curve(r.force), target, 0.1) << name;
      EXPECT_LE(r.evaluations, target < 44 ? 3 : 4) << name << " " << target;
    }
}

// A solve whose Newton stops converging above 50 N (after reporting its increments up to there), on the
// curve 60 (1 - exp(-F/90)): a target passed before the failure (25.4 mm at 50 N) is still calibrated
// from the states seen below it; one beyond (34 mm needs 75 N) is refused with a message that names the
// failing force and the largest displacement reached, not the solver's bare Newton message.
TEST(Calibration, NewtonFailureAboveTheTargetIsBracketedBelowIt) {
  auto curve = [](double F) { return 60.0 * (1.0 - std::exp(-F / 90.0)); };
  int failures = 0;
  auto solve = [&](double F, const Observer& obs) {
    const int n = std::max(5, int(std::ceil(F / 10.0)));
    for (int k = 1; k <= n; ++k) {
      const double f = F * k / n;
      if (f > 50.0) {
        ++failures;
        throw NewtonDidNotConverge("Newton did not converge (test)", double(k) / n);
      }
      obs(f, curve(f));
    }
    return curve(F);
  };
  CalibrationOptions o;
  o.initialForce = 80.0;  // beyond the failure
  o.tolerance = 0.1;
  const auto r = calibrateForce(solve, 20.0, o);
  EXPECT_NEAR(curve(r.force), 20.0, 0.1);
  EXPECT_LT(r.force, 50.0);
  EXPECT_EQ(failures, 1);
  EXPECT_TRUE(std::isnan(r.history.front().second));  // the failed solve is in the history
  try {
    calibrateForce(solve, 34.0, o);
    ADD_FAILURE() << "a target beyond the last converged state must be refused";
  } catch (const NewtonDidNotConverge&) {
    ADD_FAILURE() << "the solver's own message, not the calibration's";
  } catch (const pectus::InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("No converged state reaches the target displacement 34 mm"), std::string::npos) << m;
    EXPECT_NE(m.find("stops converging at"), std::string::npos) << m;
  }
}
