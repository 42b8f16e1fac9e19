// Nuss procedure finite element analysis of a labelled rib cage (thesis 6.1, 6.2, 6.4.1). Host-free:
// vcglib CMeshO in, the pectus_fe solver (TetGen + CHOLMOD) inside, plain results out. No Qt.
//
// Model: the closed, labelled cage surface (labels.h: tissue + part per face) is tetrahedralised by
// TetGen; each tet takes the tissue and part of the surface face nearest to its centroid. Materials:
// bone and sternum E = 11.5 GPa, pectus costal cartilage E = 12.25 MPa (thesis' defaults; Options sets
// both moduli and both Poisson ratios).
// Boundary conditions (Fig. 6-4): every node within `jointRadius` of a costovertebral joint landmark is
// fixed (head and tubercle rigid; a joint with fewer than four nodes that near, on a coarse or smoothed mesh,
// is fixed at the four nodes of its rib nearest to it, and at the next nearest while those lie on one line, about
// which a floating rib would turn); a vertebral column in the model (part kVertebralColumn, as 'Prepare
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
#include "pectus/param_range.h"

namespace pectus::nuss {

// Valid ranges validate() and the bar placement check; the filters declare their parameters with them.
inline constexpr ParamRange kPoissonRange{-1, 0.5, true, true};  ///< Poisson's ratio of every tissue
inline constexpr ParamRange kModulusRange{0, 1e6, true, false};  ///< Young's modulus of every tissue (MPa)
inline constexpr ParamRange kSecondShareRange{0, 1, true, true}; ///< the second bar's share of the force
inline constexpr ParamRange kForceRange{0, 1e5, true, false};    ///< Options::force, the given Fe (N)
inline constexpr ParamRange kMaxForceRange{0, 1e6, true, false}; ///< Options::maxForce (N)
inline constexpr ParamRange kToleranceRange{0, 50, true, false}; ///< Options::tolerance, of the calibration (mm)
/// Options::targetElevation (mm); 0: a given force (or the chest line's depth, Options::targetFromChestLine)
inline constexpr ParamRange kTargetElevationRange{0, 300};
/// Placement's jointRadius, sternumLoadRadius and ribSupportRadius (mm)
inline constexpr ParamRange kPatchRadiusRange{0, 100, true, false};

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
/// Throws TopologyError when m has no faces or duplicate faces, InputError for non-finite coordinates or no
/// tissue labels (labels.h).
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
  /// Sternoclavicular support (Sci Rep 2020;10:7357, doi 10.1038/s41598-020-64482-7): the anterior translation (along
  /// `direction`'s largest axis) of the sternum's surface nodes within this radius of the jugular notch
  /// (landmark 502) is held at zero, as the clavicles hold the manubrium; the other translations stay free.
  /// 0: no such support, the manubrium held only through the ribs (the thesis' Fig. 6-4).
  double sternoclavicularRadius = 0;
};

/// The bar exit of intercostal space s on one side (1 right, 2 left): landmark 600 + 10*side + s when
/// present, else the midpoint of the lateral-most points of ribs s and s+1 (centroid of each rib's bone
/// surface nodes within 10 mm in |x| of its most lateral node, which is where the generator puts the
/// landmarks). Throws InputError naming the missing rib when the cage has no rib s or s+1 on that side.
Eigen::Vector3d barExit(const CageSurface& cage, const std::vector<Landmark>& lms, int side, int space);
/// The chest line at the lower sternum end: where the sternum would lie on a normal chest. In the slab
/// |z - z_end| <= kChestLineSlab around the lower sternum end, the most anterior cage point right of the
/// sternum and the most anterior one left of it (more than kChestLineGap mm to each side, vertebral column
/// left out) span the line; `depth` is how far the sternum's anterior surface near its lower end (within
/// the Fe patch radius) lies behind that line along the force direction: the rise that brings the lower
/// sternum end onto the chest line.
constexpr double kChestLineSlab = 10.0, kChestLineGap = 20.0;
/// The model is taken to reach at most this multiple of the chest line depth: past it the sternum would
/// stand further in front of the chest line than it lay behind it, an over-correction no repair aims at.
/// (Nuss repairs over-correct: the thesis' patients 4 and 5, index 3.7 and 3.6, rose 35.4 and 37.5 mm.)
constexpr double kMaxCorrection = 2.0;
struct ChestLine {
  Eigen::Vector3d right = Eigen::Vector3d::Zero(), left = Eigen::Vector3d::Zero();  ///< the line's ends
  Eigen::Vector3d sternumFront = Eigen::Vector3d::Zero();  ///< anterior-most sternum point near its lower end
  double depth = 0;  ///< mm along the force direction; <= 0: the sternum lies on or in front of the line
  double reach() const { return kMaxCorrection * depth; }  ///< the largest target the model accepts (mm)
  std::string describe() const;  ///< "lower sternum end 38.2 mm behind the chest line between (..) and (..)"
};
/// Throws InputError when the lower sternum end is unknown or no cage point lies to one side of it.
ChestLine chestLine(const CageSurface& cage, const std::vector<Landmark>& lms, const Placement& pl);

/// Places the loads of `pl` on the cage surface (no mesh, no solve): throws the InputError the analysis
/// would throw for them (missing landmark, a space outside the ribs, a second bar beside the sternum).
void checkPlacement(const CageSurface& cage, const std::vector<Landmark>& lms, const Placement& pl);

/// Newton settings of the analysis: 5 increments at least, the library's convergence criteria (the
/// elevation converged to ~1e-5 of itself, far below the 0.1 mm calibration tolerance), modified Newton
/// (refactorise only when the residual stalls), up to 60 iterations per increment, 6 cut-backs, a line
/// search on the residual and load increments that grow and shrink with the iteration count (a soft
/// cartilage's hard load path).
inline fe::NewtonOptions analysisNewton() {
  fe::NewtonOptions n;
  n.loadSteps = 5;
  n.maxIterations = 60;
  n.maxCutbacks = 6;
  n.modified = true;
  n.lineSearch = true;
  n.adaptiveSteps = true;
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
  /// Young's moduli (MPa), the thesis' by default; the published cartilage range (Weber et al. 2021:
  /// indentation 11.1-14.6 MPa, compression 32.9 +- 17.9 MPa) moves the calibrated force about in proportion
  double eBone = fe::kThesisBoneE, eCartilage = fe::kThesisCartilageE;
  bool nonlinear = true;            ///< large displacement (total Lagrangian, `material`)
  /// every tissue's large-displacement model: neo-Hookean resists the compression of a thin cartilage that
  /// inverts a St Venant-Kirchhoff tet on the way to a child's measured elevation
  fe::MaterialModel material = fe::MaterialModel::NeoHookean;
  /// when targetElevation > 0: one displacement-controlled solve (a force search takes several)
  CalibrationMethod calibration = CalibrationMethod::DisplacementControl;
  fe::NewtonOptions newton = analysisNewton();  ///< loadSteps is a minimum; the curve step adds stops
  double force = 140;               ///< Fe (N) when targetElevation <= 0
  double targetElevation = 0;       ///< mm; > 0: calibrate Fe to this sternal elevation
  /// calibrate Fe to the chest line depth (chestLine(); targetElevation is ignored)
  bool targetFromChestLine = false;
  double tolerance = 0.1;           ///< calibration tolerance (mm)
  double maxForce = 1000;           ///< N; the target is unreachable if Fe = maxForce does not reach it
  double curveStep = 20;            ///< N: force-displacement curve step (thesis 20 N)
  Placement place;
  std::function<void(int, const std::string&)> progress;  ///< (percent, what)
};

/// The mesh the convergence study found within 2 % of the converged one (docs/validation.md, FE mesh
/// convergence; the thesis' criterion, Table 6-2: the sternal elevation changes by less than 1 % on
/// refinement): TET10, TetGen's quality refinement, a cage of 5 mm edges (their mean 5.7 mm) or finer.
inline constexpr double kConvergedMeanEdgeMm = 6.0;
/// Why a result on these mesh settings is not one to report, or empty when it is: linear TET4 locks in
/// bending, a mesh without quality refinement is about 12 % stiffer than the converged one, and a coarser
/// surface than the study's was not shown to converge.
std::string notReportableBecause(const fe::TetgenOptions& mesh, const CageSurface& cage);

/// The target of a calibration, resolved before any mesh or solve: the chest line depth when
/// opt.targetFromChestLine, else opt.targetElevation (0: a given force), which must not exceed the chest
/// line's reach when the cage has a chest line. Throws InputError naming the reachable range.
struct Target {
  double elevation = 0;          ///< mm; 0: no calibration (a given force)
  bool fromChestLine = false;    ///< the elevation is the chest line depth
  std::optional<ChestLine> chest;  ///< measured when the cage has a sternum and ribs on both sides of it
  /// "38.2 mm, from the model: lower sternum end ..." / "44.7 mm, as given (lower sternum end ...)"
  std::string describe() const;
};
Target resolveTarget(const CageSurface& cage, const std::vector<Landmark>& lms, const Options& opt);

/// Throws InputError naming what to change for options no analysis can run with: the mesh options
/// (fe::validate), Poisson's ratios, moduli, the given force (when no target is set), the maximum force, the
/// tolerance or the target elevation outside their ranges above, a curve step that is not positive.
/// analyze() calls it first.
void validate(const Options& opt);

/// Where a value sits: the tet, its centroid, tissue and anatomical part, and whether it lies near the
/// spine (within kNearSpine mm of the costovertebral joint of its rib).
constexpr double kNearSpine = 35.0;
struct Location {
  int tet = -1;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  int tissue = 0, part = 0;
  double distanceToJoint = -1;  ///< mm to the joint of its rib (-1: not a rib)
  /// the part and how far from its joint: "left rib 5 (bone), 72 mm from its costovertebral joint"
  std::string where() const;
  std::string describe() const;  ///< where() and the place: "... at (12.3, 45.6, 78.9) mm"
};

/// The tet model of a cage (TetGen once; every load case of the same cage and mesh options reuses it)
struct Model {
  fe::TetMesh mesh;
  std::vector<int> tetPart;  ///< anatomical part of each tet (of its nearest surface face)
  double secondsMesh = 0;
};
/// Tetrahedralises the cage; throws TopologyError for an open or self-intersecting surface (fe::tetrahedralize).
Model buildModel(const CageSurface& cage, const fe::TetgenOptions& mesh);

struct Analysis {
  fe::TetMesh mesh;
  std::vector<int> tetPart;
  fe::Result result;                  ///< at the final force
  double force = 0;                   ///< Fe (N)
  double elevation = 0;               ///< mm
  double linearCompliance = 0;        ///< mm/N of the linear model
  std::optional<fe::CalibrationResult> calibration;
  Target target;                      ///< the calibration's target (elevation 0: a given force) and the chest line
  /// (Fe N, elevation mm) from 0: every increment (force search or a given force: incl. each curveStep N;
  /// displacement control: every elevation step, about curveStep N apart at the linear compliance)
  std::vector<std::pair<double, double>> curve;
  std::vector<double> nodalStress, nodalStrain;  ///< volume-averaged to nodes
  double maxStress = 0, maxStrain = 0;           ///< away from the joints and load patches
  Location maxStressAt, maxStrainAt;
  double maxStressAll = 0, maxStrainAll = 0;     ///< including the joints and load patches
  /// away from the tissue junctions too (tets touching a node where bone or sternum meets cartilage): the
  /// largest stress inside the tissues, where the stress at a junction's corner is singular and grows with
  /// the mesh's refinement
  double maxStressBody = 0;
  Location maxStressBodyAt;
  double maxStrainCartilage = 0, maxStrainBone = 0;
  std::vector<int> fixedNodes, sternumNodes;
  std::vector<int> sternoclavicularNodes;  ///< held along the force direction only (Placement::sternoclavicularRadius)
  int fixedAtJoints = 0;   ///< of fixedNodes: within the joint radius of a costovertebral joint
  int fixedOnColumn = 0;   ///< of fixedNodes: the others, nodes of the vertebral column's tets (part kVertebralColumn)
  int jointsWidened = 0;         ///< joints with fewer than four nodes within the joint radius: fixed at their four nearest (or more)
  double widestJointRadius = 0;  ///< mm: the farthest of those nodes from its joint
  std::vector<std::vector<int>> supportNodes;    ///< right s, right s+1, left s, left s+1 (then the second bar's)
  std::vector<std::string> supportNames;
  std::vector<int> secondSternumNodes;           ///< the second bar's sternal patch (empty: one bar)
  double secondShare = 0;                        ///< share of Fe on the second bar
  int components = 0;
  int nonlinearSolves = 0, newtonIterations = 0, factorizations = 0;
  /// every Newton iteration of the nonlinear solves, in order, the increments counted over all solves;
  /// newtonHistoryLines() writes it for the Log
  std::vector<fe::NewtonIteration> newtonHistory;
  double secondsMesh = 0, secondsSolve = 0;
  Eigen::Vector3d displacementAt(const Eigen::Vector3d& p) const;  ///< of the nearest node
};

/// The Newton history of an analysis, one line per iteration (fe::newtonIterationText): the residual, its
/// reference and the correction, each with its ratio to the iteration before in the same increment (quadratic
/// convergence squares them: the ratios fall fast). Empty for a linear analysis.
std::vector<std::string> newtonHistoryLines(const Analysis& a);

/// Runs the analysis: tetrahedralise, place the BCs/loads, solve (calibrating if asked), post-process.
/// Throws InputError with a message naming what to fix: TopologyError for an open/self-intersecting surface
/// or a part without fixed nodes, SolverFailure for a singular system, a Newton failure or a target no force
/// up to the maximum reaches, InputError itself for missing labels or landmarks or an unreachable target.
Analysis analyze(const CageSurface& cage, const std::vector<Landmark>& landmarks, const Options& opt);
/// The same on a model built before (opt.mesh is not used; the model's mesh is copied into the result).
Analysis analyze(const CageSurface& cage, const Model& model, const std::vector<Landmark>& landmarks, const Options& opt);

/// The problem of an analysis at force Fe (for the .inp writer); refers to a.mesh.
fe::Problem problemAt(const Analysis& a, const Options& opt, double force);

/// Equivalent strain along a rib and its costal cartilage (Fig. 6-18): tets of the part (and of the
/// sternum at the rib's level) binned by lateral distance from the sternum's midline.
struct PathSample { double distance, meanStrain, maxStrain, meanStress; int tissue; int tets; };
std::vector<PathSample> strainAlongRib(const Analysis& a, int side, int rib, double binWidth = 2.0);

/// The nodes the stress and strain maxima leave out (1: fixed, or carrying Fe or an Fsr), where the nodal
/// forces and the clamp make the stress singular
std::vector<char> supportAndLoadNodes(const Analysis& a);
/// Whether tet t of m has a node flagged in `nodes`
bool touches(const fe::TetMesh& m, int t, const std::vector<char>& nodes);

/// "right rib 5", "left costal cartilage 3", "sternum body", ...
std::string partName(int tissue, int part);

}  // namespace pectus::nuss
