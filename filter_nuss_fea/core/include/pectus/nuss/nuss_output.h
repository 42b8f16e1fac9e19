// The outputs of a Nuss analysis, written in one place: the files (the tet model for ParaView, the
// CalculiX deck, the force-displacement and rib strain CSVs) and the deformed surface. The FE filter, the
// bar planner and pectus_nuss_cli call these, so that the same analysis gives the same files whoever runs
// it. Host-free (no Qt, no MeshLab document).
#pragma once
#include <cstdio>
#include <string>
#include <vector>

#include "pectus/nuss/nuss_analysis.h"
#include "pectus/cmesh.h"
#include "pectus/fe/io.h"

namespace pectus::nuss {

/// The files of an analysis; a file with an empty path is not written.
struct OutputFiles {
  std::string vtu;           ///< the tet model and its results for ParaView (fe::writeVtu)
  std::string inp;           ///< the same model at the final Fe as a CalculiX deck (inpOptions)
  std::string curveCsv;      ///< force_N,elevation_mm per curve point (writeCurveCsv)
  std::string ribStrainCsv;  ///< strain along rib `pathRib` of side `pathSide` (strainAlongRib, writeRibPathCsv)
  int pathSide = 1, pathRib = 5;  ///< side 1 right, 2 left; rib 1-10
};

/// The result file base of a path: a trailing ".vtu" is dropped ("out/nuss.vtu" -> "out/nuss").
std::string resultBase(std::string path);
/// Every file at a base: BASE.vtu, BASE.inp, BASE_force_displacement.csv, BASE_rib_strain.csv.
OutputFiles filesAt(const std::string& base, int pathSide = 1, int pathRib = 5);

/// The CalculiX deck options of an analysis: NLGEOM for large displacement, one fixed increment per curve
/// step of the final Fe (10 at least), the sternal patch's nodes printed, a heading that names Fe.
fe::InpOptions inpOptions(const Analysis& a, const Options& opt);

/// Writes every file of `files` that has a path, at the analysis' final force. Throws IOError naming
/// the path when one cannot be written.
void writeOutputs(const OutputFiles& files, const Analysis& a, const Options& opt);

/// CSV files of an analysis: force_N,elevation_mm per curve point; distance_mm, tissue, mean and max
/// equivalent strain, mean von Mises stress, tets per bin of the rib path.
void writeCurveCsv(const std::string& path, const Analysis& a);
void writeRibPathCsv(const std::string& path, const std::vector<PathSample>& samples);

/// Opens `path` for writing; throws IOError naming it when it cannot be created. Every file of the
/// analysis and of the bar planner is opened here.
std::FILE* openOutput(const std::string& path);
/// Closes a file opened by openOutput; throws IOError naming the path when the data did not reach it.
void closeOutput(std::FILE* f, const std::string& path);

/// The deformed surface of an analysis: `out` becomes a copy of `analysed` (the mesh `cage` was made from
/// by cageFromMesh or joinTissueLayers; face labels kept) whose every vertex moves by the displacement of
/// its FE node (cage.nodeOfVertex; a vertex of no face stays where it was). Vertex quality = `nodal` of the
/// node (a.nodalStress, a.nodalStrain), vertex colour a red (high) to blue (low) ramp capped at the 98th
/// percentile, so that the peaks at the joints do not wash out the map; normals and bounding box updated.
/// `out` must have the optional components the copy needs enabled (a MeshLab layer: face colour, face
/// quality, vertex quality and colour).
void deformedSurface(CMeshO& out, CMeshO& analysed, const CageSurface& cage, const Analysis& a,
                     const std::vector<double>& nodal);

}  // namespace pectus::nuss
