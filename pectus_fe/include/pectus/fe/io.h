// Writers of the FE model and results: VTK XML unstructured grid (.vtu, ascii) and CalculiX input deck (.inp).
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "pectus/fe/solver.h"

namespace pectus::fe {

/// Writes the tets (VTK_TETRA / VTK_QUADRATIC_TETRA), cell data "tissue" and, with a result,
/// point data "displacement" (mm) and "von_mises_nodal" (MPa, volume-averaged), cell data "von_mises"
/// (MPa) and "equivalent_strain". Throws pectus::IOError if the file cannot be written.
void writeVtu(const std::string& path, const TetMesh& m, const Result* result = nullptr);

struct InpOptions {
  bool nlgeom = false;  ///< *STEP, NLGEOM (total Lagrangian large displacement, as our solveNonlinear)
  int increments = 10;  ///< NLGEOM: fixed increments of 1/increments (*STATIC, DIRECT)
  std::vector<int> printNodes;  ///< nodes (0-based) whose displacements go to the .dat file (*NODE PRINT, NSET=OUT)
  std::string heading = "pectus-meshlab Nuss FE model";
};

/// CalculiX/Abaqus deck of the problem: *NODE, *ELEMENT TYPE=C3D4|C3D10 with one ELSET per tissue,
/// *MATERIAL/*ELASTIC/*SOLID SECTION per tissue (in an NLGEOM deck a neo-Hookean tissue is *HYPERELASTIC,
/// NEO HOOKE with C10 = mu / 2, D1 = 2 / K: exactly MaterialModel::NeoHookeanDecoupled, the nearest ccx form
/// of MaterialModel::NeoHookean), *BOUNDARY (prescribed dofs), *STEP [NLGEOM], *STATIC,
/// *CLOAD (nodal forces), *NODE PRINT / *NODE FILE U, *EL FILE S, E. Node and element ids are 1-based.
void writeCalculixInp(const std::string& path, const Problem& p, const InpOptions& opt = {});

/// A CalculiX deck read back: the mesh, the problem (its `mesh` points at `mesh`, hence held by pointer)
/// and the output options (printNodes 0-based; increments of an NLGEOM step).
struct InpModel {
  TetMesh mesh;
  Problem problem;
  InpOptions options;
};

/// Reads the subset of the CalculiX/Abaqus input language that writeCalculixInp writes (so a deck written
/// by the filter, BASE.inp, can be solved again, and the same deck timed against ccx): *NODE, *ELEMENT
/// TYPE=C3D4|C3D10 with ELSET, *MATERIAL + *ELASTIC (isotropic) or *HYPERELASTIC, NEO HOOKE (C10, D1:
/// MaterialModel::NeoHookeanDecoupled with E, nu of the same small-strain limit), *SOLID SECTION, *NSET, *BOUNDARY
/// (node, first dof, last dof[, value]), *STEP[, NLGEOM, INC], *STATIC[, DIRECT], *CLOAD, *NODE PRINT,
/// *NODE FILE, *EL FILE, *END STEP; comment lines (**) and *HEADING text are skipped. Each ELSET becomes
/// a tissue label (BONE 1, CARTILAGE 2, STERNUM 3 as written, others 4, 5, ... in order of appearance).
/// Anything else (another keyword, element type, a bad number or node id) throws pectus::IOError
/// naming the line; so does a file that cannot be read.
std::unique_ptr<InpModel> readCalculixInp(const std::string& path);
/// The same on the deck's text; `name` stands for the file in the messages.
std::unique_ptr<InpModel> parseCalculixInp(const std::string& text, const std::string& name);

}  // namespace pectus::fe
