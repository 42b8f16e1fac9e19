// pectus_fe_cantilever: the 10 x 10 x 100 mm cantilever (clamped at z = 0, tip shear load P along y,
// uniform traction on the tip face) on a structured tet mesh; solves it with pectus_fe and/or writes
// the same model as a CalculiX deck. Used by bench/fe_vs_ccx.py.
//   pectus_fe_cantilever --n NX NY NZ --order 1|2 --load P [--nlgeom] [--steps S] [--inp file] [--no-solve]
//                        [--material svk|neo-hookean|neo-hookean-ccx]
// Prints one line "key=value ..." with the tip centre node displacement and timings.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "pectus/errors.h"
#include "pectus/fe/io.h"
#include "pectus/fe/solver.h"

using namespace pectus::fe;

int main(int argc, char** argv) {
  int n[3] = {2, 2, 20}, order = 1, steps = 10;
  double P = 20, L = 100, B = 10, E = 11500, nu = 0.3;
  bool nlgeom = false, solve = true;
  MaterialModel model = MaterialModel::StVenantKirchhoff;
  std::string inp, vtu;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--n" && i + 3 < argc) {
      for (int k = 0; k < 3; ++k) n[k] = std::atoi(argv[++i]);
    } else if (a == "--order" && i + 1 < argc) order = std::atoi(argv[++i]);
    else if (a == "--load" && i + 1 < argc) P = std::atof(argv[++i]);
    else if (a == "--steps" && i + 1 < argc) steps = std::atoi(argv[++i]);
    else if (a == "--nlgeom") nlgeom = true;
    else if (a == "--inp" && i + 1 < argc) inp = argv[++i];
    else if (a == "--vtu" && i + 1 < argc) vtu = argv[++i];
    else if (a == "--no-solve") solve = false;
    else if (a == "--material" && i + 1 < argc) {
      try {
        model = parseMaterialModel(argv[++i]);
      } catch (const pectus::InputError& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 2;
      }
    }
    else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (n[0] % 2 || n[1] % 2) {
    std::fprintf(stderr, "NX and NY must be even (the tip centre must be a node)\n");
    return 2;
  }
  try {
    auto t0 = std::chrono::steady_clock::now();
    TetMesh m = structuredBox(B, B, L, n[0], n[1], n[2], 1);
    if (order == 2) m = toQuadratic(m);
    Problem p;
    p.mesh = &m;
    p.materials = {{1, {E, nu, model}}};
    int tip = -1;
    for (int i = 0; i < m.numNodes(); ++i) {
      if (m.nodes[i].z() < 1e-9) p.fixNode(i);
      if ((m.nodes[i] - Eigen::Vector3d(B / 2, B / 2, L)).norm() < 1e-9) tip = i;
    }
    std::vector<BoundaryFace> tipFaces;
    for (const auto& f : boundaryFaces(m))
      if (m.nodes[f.n[0]].z() > L - 1e-9 && m.nodes[f.n[1]].z() > L - 1e-9 && m.nodes[f.n[2]].z() > L - 1e-9) tipFaces.push_back(f);
    p.force = tractionLoads(m, tipFaces, Eigen::Vector3d(0, P / (B * B), 0));
    const double tMesh = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("tets=%d nodes=%d order=%d tip_node=%d mesh_s=%.3f", m.numTets(), m.numNodes(), order, tip + 1, tMesh);
    if (!inp.empty()) {
      InpOptions o;
      o.nlgeom = nlgeom;
      o.increments = steps;
      o.printNodes = {tip};
      writeCalculixInp(inp, p, o);
    }
    if (solve) {
      auto t1 = std::chrono::steady_clock::now();
      Solver s(p);
      const double tSetup = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      NewtonOptions no;
      no.loadSteps = steps;
      Result r = nlgeom ? s.solveNonlinear(no) : s.solveLinear();
      const double tSolve = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      std::printf(" dofs=%d setup_s=%.3f solve_s=%.3f last_factor_s=%.3f newton_it=%d tip_ux=%.9g tip_uy=%.9g tip_uz=%.9g",
                  s.numFreeDofs(), tSetup, tSolve, s.lastSolveSeconds(), r.newtonIterations, r.u(3 * tip), r.u(3 * tip + 1),
                  r.u(3 * tip + 2));
      if (!vtu.empty()) writeVtu(vtu, m, &r);
    }
    std::printf("\n");
  } catch (const pectus::InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
