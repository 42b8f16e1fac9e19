// Nuss procedure finite element analysis of a labelled rib cage (thesis 6.1, 6.2, 6.4.1). Host-free:
// vcglib CMeshO in, the pectus_fe solver (TetGen + CHOLMOD) inside, plain results out. No Qt.
//
// Model: the closed, labelled cage surface (labels.h: tissue + part per face) is tetrahedralised by
// TetGen; each tet takes the tissue and part of the surface face nearest to its centroid. Materials:
// bone and sternum E = 11.5 GPa, pectus costal cartilage E = 12.25 MPa (thesis), Poisson ratios given.
// Boundary conditions (Fig. 6-4): every node within `jointRadius` of a costovertebral joint landmark is
// fixed (head and tubercle rigid); a vertebral column in the model (part kVertebralColumn, as 'Prepare
// Patient Rib Cage' keeps it) is the fixed support: every node of its tets is fixed too. Loads (Fig. 6-3, Fe = 2 Fs = 4 Fsr): the elevating force Fe along
// `direction` (default anterior, +y) spread evenly over the sternum's surface nodes within
// `sternumLoadRadius` of the lower sternum end; four rib support forces Fsr = Fe/4, opposite to Fe,
// each spread over the surface nodes of one rib (the ribs s and s+1 above and below the bar's exit in
// intercostal space s, both sides) within `ribSupportRadius` of the rib point nearest to the exit.
// The loads are self-equilibrated; the joints carry only what the cage's deformation demands.
// Elevation = mean displacement along `direction` of the nodes carrying Fe (the end of the sternum).
#pragma once
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "pectus/cmesh.h"
#include "pectus/fe/calibrate.h"
#include "pectus/fe/solver.h"
#include "pectus/fe/tetgen_mesher.h"
#include "pectus/labels.h"

namespace pectus::nuss {

/// The cage surface as the FE core wants it: live vertices compacted, micro-edges welded, labels per
/// face. m.vert[i] is FE node nodeOfVertex[i] (-1: deleted, or referenced by no face), so results map
/// back to the layer.
struct CageSurface {
  fe::SurfaceMesh surface;
  std::vector<int> facePart;
  std::vector<int> nodeOfVertex;
  int weldedFaces = 0;           ///< faces dropped by welding edges shorter than 1e-3 x the mean edge length
  int unreferencedVertices = 0;  ///< live vertices of no face: dropped (no FE node)
  /// If set, relabels the tets (tissue and part) after TetGen's nearest-face labels: the containment
  /// rule of the joined tissue layers (tissue_join.h)
  std::function<void(fe::TetMesh&, std::vector<int>& tetPart)> labelTets;
};
/// Throws InputError when m has no faces, non-finite coordinates or no tissue labels (labels.h).
CageSurface cageFromMesh(const CMeshO& m);

struct Placement {
  double jointRadius = 6.0;        ///< mm around each costovertebral joint landmark: fixed nodes
  double sternumLoadRadius = 8.0;  ///< mm around the lower sternum end: nodes carrying Fe
  double ribSupportRadius = 6.0;   ///< mm around each rib support point: nodes carrying one Fsr
  int intercostalSpace = 4;        ///< bar exits between ribs s and s+1 (landmarks 600 + 10*side + s)
  Eigen::Vector3d direction{0, 1, 0};  ///< Fe direction (anterior); Fsr are opposite
  /// user points overriding the landmarks: lower sternum end, right and left bar exits
  std::optional<Eigen::Vector3d> sternumPoint, exitRight, exitLeft;
  /// Two-bar repair: the second bar's intercostal space (0: one bar) and the share of Fe it carries.
  /// Its exits come from the landmarks (or the ribs, see barExit); its sternal patch is centred on the
  /// sternum at the height of the lower sternum end moved by the z difference between the two bars'
  /// exits (bars are parallel). Each bar is self-equilibrated: Fe_i = 2 Fs_i = 4 Fsr_i, Fe_1 + Fe_2 = Fe.
  /// The elevation (calibration target) stays that of the lower sternum end (the first bar's patch).
  int secondSpace = 0;
  double secondShare = 0.5;
};

/// The bar exit of intercostal space s on one side (1 right, 2 left): landmark 600 + 10*side + s when
/// present, else the midpoint of the lateral-most points of ribs s and s+1 (centroid of each rib's bone
/// surface nodes within 10 mm in |x| of its most lateral node, which is where the generator puts the
/// landmarks). Throws InputError naming the missing rib when the cage has no rib s or s+1 on that side.
Eigen::Vector3d barExit(const CageSurface& cage, const std::vector<Landmark>& lms, int side, int space);
/// Places the loads of `pl` on the cage surface (no mesh, no solve): throws the InputError the analysis
/// would throw for them (missing landmark, a space outside the ribs, a second bar beside the sternum).
void checkPlacement(const CageSurface& cage, const std::vector<Landmark>& lms, const Placement& pl);

/// Newton settings of the analysis: 5 increments at least, relative tolerances 1e-6 (the elevation is
/// converged to far below the 0.1 mm calibration tolerance), modified Newton (refactorise only when
/// the residual stalls), up to 60 iterations per increment, 6 cut-backs.
inline fe::NewtonOptions analysisNewton() {
  fe::NewtonOptions n;
  n.loadSteps = 5;
  n.tolResidual = 1e-6;
  n.tolDisplacement = 1e-6;
  n.maxIterations = 60;
  n.maxCutbacks = 6;
  n.modified = true;
  return n;
}

/// How a target elevation is reached: a search over the force (a nonlinear solve per trial force,
/// calibrate.h), or one displacement-controlled solve (fe::Solver::solveControlled) that drives the mean
/// displacement of the sternal load patch along the force direction to the target and finds Fe (with
/// Fe = 2 Fs = 4 Fsr) as its load factor. The linear model needs no search: both give target / compliance.
enum class CalibrationMethod { ForceSearch, DisplacementControl };
/// "force", "displacement"; parseCalibrationMethod throws InputError listing them
const char* calibrationMethodName(CalibrationMethod m);
CalibrationMethod parseCalibrationMethod(const std::string& name);

struct Options {
  fe::TetgenOptions mesh;           ///< quality, max volume, order (1 TET4, 2 TET10)
  double nuBone = 0.3, nuCartilage = 0.4;
  bool nonlinear = true;            ///< large displacement (total Lagrangian, `material`)
  fe::MaterialModel material = fe::MaterialModel::StVenantKirchhoff;  ///< every tissue's large-displacement model
  CalibrationMethod calibration = CalibrationMethod::ForceSearch;      ///< when targetElevation > 0
  fe::NewtonOptions newton = analysisNewton();  ///< loadSteps is a minimum; the curve step adds stops
  double force = 140;               ///< Fe (N) when targetElevation <= 0
  double targetElevation = 0;       ///< mm; > 0: calibrate Fe to this sternal elevation
  double tolerance = 0.1;           ///< calibration tolerance (mm)
  double maxForce = 1000;           ///< N; the target is unreachable if Fe = maxForce does not reach it
  double curveStep = 20;            ///< N: force-displacement curve step (thesis 20 N)
  Placement place;
  std::function<void(int, const std::string&)> progress;  ///< (percent, what)
};

/// Where a value sits: the tet, its centroid, tissue and anatomical part, and whether it lies near the
/// spine (within kNearSpine mm of the costovertebral joint of its rib).
constexpr double kNearSpine = 35.0;
struct Location {
  int tet = -1;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  int tissue = 0, part = 0;
  double distanceToJoint = -1;  ///< mm to the joint of its rib (-1: not a rib)
  std::string describe() const;  ///< e.g. "left rib 5 (bone), posterior, 12 mm from the costovertebral joint"
};

/// The tet model of a cage (TetGen once; every load case of the same cage and mesh options reuses it)
struct Model {
  fe::TetMesh mesh;
  std::vector<int> tetPart;  ///< anatomical part of each tet (of its nearest surface face)
  double secondsMesh = 0;
};
/// Tetrahedralises the cage; throws InputError for an open or self-intersecting surface.
Model buildModel(const CageSurface& cage, const fe::TetgenOptions& mesh);

struct Analysis {
  fe::TetMesh mesh;
  std::vector<int> tetPart;
  fe::Result result;                  ///< at the final force
  double force = 0;                   ///< Fe (N)
  double elevation = 0;               ///< mm
  double linearCompliance = 0;        ///< mm/N of the linear model
  std::optional<fe::CalibrationResult> calibration;
  /// (Fe N, elevation mm) from 0: every increment (force search or a given force: incl. each curveStep N;
  /// displacement control: every elevation step, about curveStep N apart at the linear compliance)
  std::vector<std::pair<double, double>> curve;
  std::vector<double> nodalStress, nodalStrain;  ///< volume-averaged to nodes
  double maxStress = 0, maxStrain = 0;           ///< away from the joints and load patches
  Location maxStressAt, maxStrainAt;
  double maxStressAll = 0, maxStrainAll = 0;     ///< including the joints and load patches
  double maxStrainCartilage = 0, maxStrainBone = 0;
  std::vector<int> fixedNodes, sternumNodes;
  int fixedAtJoints = 0;   ///< of fixedNodes: within the joint radius of a costovertebral joint
  int fixedOnColumn = 0;   ///< of fixedNodes: the others, nodes of the vertebral column's tets (part kVertebralColumn)
  std::vector<std::vector<int>> supportNodes;    ///< right s, right s+1, left s, left s+1 (then the second bar's)
  std::vector<std::string> supportNames;
  std::vector<int> secondSternumNodes;           ///< the second bar's sternal patch (empty: one bar)
  double secondShare = 0;                        ///< share of Fe on the second bar
  int components = 0;
  int nonlinearSolves = 0, newtonIterations = 0, factorizations = 0;
  double secondsMesh = 0, secondsSolve = 0;
  Eigen::Vector3d displacementAt(const Eigen::Vector3d& p) const;  ///< of the nearest node
};

/// Runs the analysis: tetrahedralise, place the BCs/loads, solve (calibrating if asked), post-process.
/// Throws InputError with a message naming what to fix (open/self-intersecting surface, missing labels
/// or landmarks, a part without fixed nodes, unreachable target, Newton failure).
Analysis analyze(const CageSurface& cage, const std::vector<Landmark>& landmarks, const Options& opt);
/// The same on a model built before (opt.mesh is not used; the model's mesh is copied into the result).
Analysis analyze(const CageSurface& cage, const Model& model, const std::vector<Landmark>& landmarks, const Options& opt);

/// The problem of an analysis at force Fe (for the .inp writer); refers to a.mesh.
fe::Problem problemAt(const Analysis& a, const Options& opt, double force);

/// Equivalent strain along a rib and its costal cartilage (Fig. 6-18): tets of the part (and of the
/// sternum at the rib's level) binned by lateral distance from the sternum's midline.
struct PathSample { double distance, meanStrain, maxStrain, meanStress; int tissue; int tets; };
std::vector<PathSample> strainAlongRib(const Analysis& a, int side, int rib, double binWidth = 2.0);

/// "right rib 5", "left costal cartilage 3", "sternum body", ...
std::string partName(int tissue, int part);

}  // namespace pectus::nuss

namespace pectus::nuss {
/// CSV files of an analysis (throw InputError when the path cannot be written):
/// force_N,elevation_mm per curve point; distance_mm,tissue,mean/max equivalent strain,mean von Mises.
void writeCurveCsv(const std::string& path, const Analysis& a);
void writeRibPathCsv(const std::string& path, const std::vector<PathSample>& samples);
}  // namespace pectus::nuss
