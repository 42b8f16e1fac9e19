// Writers of the FE model and results: VTK XML unstructured grid (.vtu, ascii) and CalculiX input deck (.inp).
#pragma once
#include <string>
#include <vector>

#include "pectus/fe/solver.h"

namespace pectus::fe {

/// Writes the tets (VTK_TETRA / VTK_QUADRATIC_TETRA), cell data "tissue" and, with a result,
/// point data "displacement" (mm) and "von_mises_nodal" (MPa, volume-averaged), cell data "von_mises"
/// (MPa) and "equivalent_strain". Throws pectus::InputError if the file cannot be written.
void writeVtu(const std::string& path, const TetMesh& m, const Result* result = nullptr);

struct InpOptions {
  bool nlgeom = false;  ///< *STEP, NLGEOM (total Lagrangian large displacement, as our solveNonlinear)
  int increments = 10;  ///< NLGEOM: fixed increments of 1/increments (*STATIC, DIRECT)
  std::vector<int> printNodes;  ///< nodes (0-based) whose displacements go to the .dat file (*NODE PRINT, NSET=OUT)
  std::string heading = "pectus-meshlab Nuss FE model";
};

/// CalculiX/Abaqus deck of the problem: *NODE, *ELEMENT TYPE=C3D4|C3D10 with one ELSET per tissue,
/// *MATERIAL/*ELASTIC/*SOLID SECTION per tissue, *BOUNDARY (prescribed dofs), *STEP [NLGEOM], *STATIC,
/// *CLOAD (nodal forces), *NODE PRINT / *NODE FILE U, *EL FILE S, E. Node and element ids are 1-based.
void writeCalculixInp(const std::string& path, const Problem& p, const InpOptions& opt = {});

}  // namespace pectus::fe
