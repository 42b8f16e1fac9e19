// pectus_fe_solve: solves a CalculiX deck of the kind the Nuss FE filter writes (BASE.inp, or
// pectus_nuss_cli --inp) with pectus_fe, so the same deck can be run by both programs and timed whole
// process against whole process (bench/fe_vs_ccx.py --cases cage).
//   pectus_fe_solve deck.inp [--vtu out.vtu] [--trace] [--no-predictor] [--tolerances residual displacement] [--between d]
// Linear unless the deck's *STEP says NLGEOM (then Newton with the deck's increments and the library's
// defaults; --trace prints one line per iteration to stderr: the residual, its reference and the
// correction, with their ratios to the iteration before; --no-predictor starts each increment from the
// converged state, --tolerances sets NewtonOptions' tolResidual and tolDisplacement, --between its
// tolDisplacementBetween).
// Prints one line of key=value figures (tets, dofs, phase times) and the mean displacement of the
// *NODE PRINT nodes.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "pectus/errors.h"
#include "pectus/fe/io.h"
#include "pectus/fe/solver.h"

using namespace pectus::fe;

int main(int argc, char** argv) {
  std::string deck, vtu;
  bool trace = false, predictor = true;
  double tolR = 0, tolD = 0, tolBetween = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--vtu" && i + 1 < argc) vtu = argv[++i];
    else if (a == "--trace") trace = true;
    else if (a == "--no-predictor") predictor = false;
    else if (a == "--tolerances" && i + 2 < argc) tolR = std::atof(argv[++i]), tolD = std::atof(argv[++i]);
    else if (a == "--between" && i + 1 < argc) tolBetween = std::atof(argv[++i]);
    else if (deck.empty() && !a.empty() && a[0] != '-') deck = a;
    else {
      std::fprintf(stderr, "usage: pectus_fe_solve deck.inp [--vtu out.vtu] [--trace] [--no-predictor] [--tolerances r d] [--between d] (unknown argument %s)\n", a.c_str());
      return 2;
    }
  }
  if (deck.empty()) {
    std::fprintf(stderr, "usage: pectus_fe_solve deck.inp [--vtu out.vtu] [--trace] [--no-predictor] [--tolerances r d] [--between d]\n");
    return 2;
  }
  using Clock = std::chrono::steady_clock;
  const auto secs = [](Clock::time_point a) { return std::chrono::duration<double>(Clock::now() - a).count(); };
  try {
    const auto t0 = Clock::now();
    const auto model = readCalculixInp(deck);
    const double tRead = secs(t0);
    const auto t1 = Clock::now();
    Solver s(model->problem);
    const double tSetup = secs(t1);
    const auto t2 = Clock::now();
    NewtonOptions no;
    no.loadSteps = model->options.increments;
    no.extrapolate = predictor;
    if (tolR > 0) no.tolResidual = tolR;
    if (tolD > 0) no.tolDisplacement = tolD;
    if (tolBetween > 0) no.tolDisplacementBetween = tolBetween;
    NewtonIteration before;
    if (trace)
      no.onIteration = [&before](const NewtonIteration& it) {
        std::fprintf(stderr, "%s\n", newtonIterationText(it, it.iteration > 0 ? &before : nullptr).c_str());
        before = it;
      };
    const Result r = model->options.nlgeom ? s.solveNonlinear(no) : s.solveLinear();
    const double tSolve = secs(t2);
    std::printf("tets=%d nodes=%d order=%d dofs=%d nlgeom=%d read_s=%.3f setup_s=%.3f solve_s=%.3f last_factor_s=%.3f newton_it=%d factorizations=%d",
                model->mesh.numTets(), model->mesh.numNodes(), model->mesh.order, s.numFreeDofs(),
                model->options.nlgeom ? 1 : 0, tRead, tSetup, tSolve, s.lastSolveSeconds(), r.newtonIterations, r.factorizations);
    const auto& out = model->options.printNodes;
    if (!out.empty()) {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (int n : out) mean += r.displacement(n);
      mean /= static_cast<double>(out.size());
      std::printf(" print_nodes=%zu mean_ux=%.9g mean_uy=%.9g mean_uz=%.9g", out.size(), mean.x(), mean.y(), mean.z());
    }
    if (!vtu.empty()) {
      const auto t3 = Clock::now();
      writeVtu(vtu, model->mesh, &r);
      std::printf(" vtu_s=%.3f", secs(t3));
    }
    std::printf("\n");
  } catch (const pectus::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
