// Fuzz target: the CalculiX deck reader (parseCalculixInp, what pectus_fe_solve and readCalculixInp run on a
// BASE.inp) on arbitrary text, and on every deck it accepts the solver's own checks and a linear solve
// (small decks only), then the deck written back and read again.
// Properties: the reader either throws InputError or returns a consistent model (its problem points at its
// mesh, every tet has valid nodes and a tissue, every fixed dof and print node exists, one force per node,
// finite coordinates); a solve either throws InputError or gives finite displacements, stresses and
// strains; a model written back reads again with the same counts.
#include <unistd.h>

#include <cmath>
#include <string>

#include "fuzz_mesh.h"
#include "pectus/errors.h"
#include "pectus/fe/io.h"
#include "pectus/fe/solver.h"

using namespace pectus;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::unique_ptr<fe::InpModel> m;
  try {
    m = fe::parseCalculixInp(text, "fuzz.inp");
  } catch (const InputError&) {
    return 0;
  }
  const fe::TetMesh& mesh = m->mesh;
  const int n = mesh.numNodes();
  PECTUS_FUZZ_CHECK(m->problem.mesh == &m->mesh);
  PECTUS_FUZZ_CHECK(mesh.numTets() > 0);
  PECTUS_FUZZ_CHECK(mesh.tissue.size() == mesh.tets.size());
  for (const auto& p : mesh.nodes) PECTUS_FUZZ_CHECK(p.allFinite());
  for (const auto& t : mesh.tets)
    for (int a = 0; a < mesh.nodesPerTet(); ++a) PECTUS_FUZZ_CHECK(t[a] >= 0 && t[a] < n);
  for (int t : mesh.tissue) PECTUS_FUZZ_CHECK(t > 0);
  for (const auto& d : m->problem.fixed) PECTUS_FUZZ_CHECK(d.node >= 0 && d.node < n && d.dof >= 0 && d.dof <= 2);
  PECTUS_FUZZ_CHECK(static_cast<int>(m->problem.force.size()) == n);
  for (int p : m->options.printNodes) PECTUS_FUZZ_CHECK(p >= 0 && p < n);
  PECTUS_FUZZ_CHECK(m->options.increments >= 1);
  if (mesh.numTets() > 2000 || n > 3000) return 0;  // the solve of a large deck only costs time
  try {
    fe::Solver s(m->problem);
    const fe::Result r = s.solveLinear();
    PECTUS_FUZZ_CHECK(r.u.size() == 3 * n && r.u.allFinite());
    for (double v : r.vonMises) PECTUS_FUZZ_CHECK(std::isfinite(v) && v >= 0);
    for (double v : r.eqStrain) PECTUS_FUZZ_CHECK(std::isfinite(v) && v >= 0);
  } catch (const InputError&) {
  }
  try {
    const std::string path = "/tmp/pectus_fuzz_inp_" + std::to_string(getpid()) + ".inp";
    fe::writeCalculixInp(path, m->problem, m->options);
    const auto again = fe::readCalculixInp(path);
    PECTUS_FUZZ_CHECK(again->mesh.numNodes() == n && again->mesh.numTets() == mesh.numTets());
    PECTUS_FUZZ_CHECK(again->problem.fixed.size() == m->problem.fixed.size());
  } catch (const InputError&) {  // e.g. a tissue without a material cannot be written
  }
  return 0;
}
