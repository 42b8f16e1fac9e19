// Micro-GA surface mesh smoothing (thesis chapter 4.2, steps 1-9). Host-free (CMeshO + Eigen, no Qt).
//
// For each free node the micro-GA (mga.h) searches inside every adjacent element: a triangle element
// itself, or for a quad the two triangles of the quad's fan around the node (p0 p1 p2 and p0 p2 p3 with
// p0 the node), since the thesis restricts the search to a triangular area. A candidate is
//   V = (1 - r2) V1 + r2 (1 - r1) V2 + r1 r2 V3,   r1 in [0,1], r2 in [0,0.5]      (eqs. 3-18/3-19)
// with V1 the node; it is mapped onto the C1 surface (c1_surface.h) of the ORIGINAL mesh (built once) by a
// local projection (Gauss-Newton on the patch the node currently lies on, walking to neighbour patches,
// falling back to the global closestPoint; in the micro-GA's search the last Gauss-Newton step is taken
// to first order, ~1e-6 of a patch off it, and the node moves to the exact surface point at the best
// location found, if its fitness there still gains). Fitness = sum of alpha (eq. 3-21) or beta (eq. 3-24)
// over the node's elements. An element that is inverted or folded with respect to the surface normal at the
// candidate or at any other of its nodes (signed area / Knupp corner areas not positive; the other nodes'
// normals are kept per node) makes the candidate worse than any valid one, so no move folds a neighbour's element,
// and r2 = 0 (the node's current position, exactly) is the seed of every search, so a node never gets
// worse and a valid configuration never folds. The best over the adjacent elements is kept.
// Guard on the worst element (not in the thesis, which maximizes the plain sum): a candidate is also
// rejected if the worst of the node's elements would drop below min(its current value,
// Options::worstGuard), so the sum cannot buy a better mean with one very poor element; the mesh minimum
// therefore never drops below min(initial minimum, worstGuard). The guard comes before the fold rule: a
// node whose star is folded may unfold only without dropping its worst element below the guard.
// worstGuard = 0: the thesis' plain sum.
// Folds (not in the thesis): after each colour's parallel search its moves are taken again one after the
// other, and a move that makes an element face against its edge neighbours (pectus/folds.h) where it did
// not is undone; a folded element may unfold. So no smoothing folds the surface anew.
// Optional final pass (not in the thesis; off by default): after the sweeps, up to minPassSweeps sweeps
// over the nodes whose worst element is below minPassBelow, each maximising that worst element (ties
// broken by the sum), with the same search, projection and fold rules.
// Sweeps repeat until the mean quality improves by less than the tolerance or the sweep cap is reached.
//
// Fixed nodes: boundary nodes; feature and singular nodes, by one of two rules (Options::features):
//  - Creases (the default): the nodes of the crease chains of creases.h - chains of edges sharp across,
//    consistent along, told from the isolated sharp edges of a noisy scan - are feature nodes, and the
//    chains' corners (three or more crease edges meet, or an open chain ends) are the singular nodes;
//  - Angles: feature nodes (every node on a sharp edge, i.e. an edge whose dihedral
// angle - the angle between the two faces' normals - exceeds the feature angle; faux edges inside quads
// are not feature edges); singular nodes of large curvature variation (thesis 4.3: "singular points ...
// which contain large curvature variation need be identified and fixed"): the normal cone of the node's
// faces - the largest angle between the normals of any two faces around the node - exceeds the singular
// angle, e.g. the apex of a cone or a spike, where no single edge is sharp but the surface turns a lot
// within one ring. Then nodes not in any element, and the user's fixed set.
//
// Method::ConjugateGradient (the baseline of thesis Table 4-1, after Garimella et al.): the same node
// loop, fixed nodes, colouring, projection and fitness, but each node is moved by Polak-Ribiere conjugate
// gradient ascent of the fitness in the node's local parametric coordinates (u, v) - the tangent plane
// of the C1 surface at the node, scaled by the mean length of the node's edges - with numerical
// (central difference) gradients and a line search (halving steps from half an edge length, then one
// parabolic refinement); every trial point is projected onto the C1 surface, and a step is taken only
// if it raises the fitness, so the same no-fold and worst-element guarantees hold.
//
// Parallel: nodes are greedily coloured (in index order) so that nodes of one colour share no element;
// each colour is processed in parallel with OpenMP, with per-node seeds itemSeed(itemSeed(seed, sweep),
// vertex): the result does not depend on the number of threads.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "pectus/mga/mga.h"
#include "pectus/cmesh.h"
#include "pectus/elements.h"
#include "pectus/param_range.h"
#include "pectus/quality.h"

namespace pectus::smooth {

constexpr double kMinQualityGuard = 0.7;  ///< default guard (bench/mga_smooth.py: the worst element ahead of CGAL on smooth scans)

// Valid ranges of the Options validateOptions checks (the integer counts and the tolerance only at their
// lower end); the filters declare their parameters with the same constants.
inline constexpr ParamRange kMaxSweepsRange{1, 100000};
inline constexpr ParamRange kToleranceRange{0, 1};
inline constexpr ParamRange kAccuracyRange{0, 0.5, true, true};
inline constexpr ParamRange kGenerationsRange{1, 100000};
inline constexpr ParamRange kRestartsRange{0, 100000};
inline constexpr ParamRange kPopulationRange{3, 1000};
inline constexpr ParamRange kCgIterationsRange{1, 10000};
/// worstGuard and minPassBelow: element qualities
inline constexpr ParamRange kQualityRange{0, 1};
/// featureAngleDeg and singularAngleDeg (degrees)
inline constexpr ParamRange kAngleRange{0, 180, true, false};

/// MicroGA: which elements around a node the micro-GA searches
enum class ElementSearch {
  Every,   ///< every adjacent element, the best kept (thesis step 3)
  /// start in the element towards the centroid of the node's neighbours (the centroid itself, where
  /// tangential relaxation would move the node, seeds that element's micro-GA beside the node), go on
  /// across an edge while the best point lies on it, stop at an optimum inside an element; an element
  /// where no move gains sends the search to every element (searchMga in mga_smooth.cpp)
  Guided,
  /// Guided, but an element where no move gains ends the node's search (the node stays where it is):
  /// every element only for a star that starts folded or invalid. The micro-GA of a star that starts
  /// valid measures its candidates where they lie, on the element's plane, and only each element's best
  /// is projected onto the C1 surface and measured there (a folded star is searched on the surface, whose
  /// normals it needs to unfold). The fastest; on smooth scans (the bunny) the same mean as Guided, on
  /// rough ones (the femur) lower
  GuidedLocal,
};

/// which nodes are fixed as features (see above)
enum class FeatureDetection {
  Creases,  ///< crease chains (creases.h); featureAngleDeg and singularAngleDeg are not used
  Angles,   ///< every node on an edge bent more than featureAngleDeg, or with a normal cone over singularAngleDeg
};

enum class Method {
  MicroGA,            ///< thesis ch. 4.2: micro-GA inside every adjacent element
  ConjugateGradient,  ///< baseline of thesis Table 4-1: Polak-Ribiere CG in the node's tangent plane
};

struct Options {
  Method method = Method::MicroGA;
  ElementKind kind = ElementKind::Triangles;
  int maxSweeps = 10;
  double tolerance = 1e-4;      ///< stop when the mean quality improves by less than this in a sweep
  double accuracy = 1e-3;       ///< accuracy of r1, r2 (eq. 1-1)
  int generations = 20;         ///< micro-GA generations per adjacent element
  int restarts = 4;             ///< micro-GA restarts per adjacent element
  int population = 5;
  mga::Selection selection = mga::Selection::Roulette;
  FeatureDetection features = FeatureDetection::Creases;
  double featureAngleDeg = 60;  ///< Angles: dihedral angle above which an edge is sharp (180: no feature edges)
  double worstGuard = kMinQualityGuard;  ///< see above; 0 = the thesis' plain sum
  double minPassBelow = 0;      ///< final max-min pass for nodes whose worst element is below this (0: off)
  int minPassSweeps = 3;        ///< at most this many final max-min sweeps (stops when the minimum stalls)
  double singularAngleDeg = 90; ///< Angles: normal-cone angle of a node's faces above which it is singular (180: none)
  bool activeSet = true;         ///< after the first sweep, search only nodes whose star still gains (see above)
  ElementSearch elementSearch = ElementSearch::Every;  ///< MicroGA only
  int cgIterations = 10;        ///< ConjugateGradient: CG iterations per node and sweep
  std::uint64_t seed = 1;
  /// called after every sweep with (sweep, mean quality); return false to stop
  std::function<bool(int, double)> progress;
};

struct Result {
  std::vector<Vec3> positions;   ///< per m.vert index (deleted vertices: unchanged)
  QualityStats before, after;    ///< over elements: alpha (triangles) or beta (quads; lone triangles alpha)
  std::vector<double> perFace;   ///< element quality after, per m.face index (deleted faces: 0)
  std::size_t elements = 0, quads = 0;
  /// elements folded against the C1 surface normal at one of their nodes, before and after
  std::size_t foldedBefore = 0, foldedAfter = 0;
  /// folds (pectus/folds.h: an element facing against its edge neighbours) in the input and the result,
  /// and those of the result that the input did not have (0: such moves are undone, see smoothMesh)
  std::size_t foldsBefore = 0, foldsAfter = 0, foldsNew = 0;
  std::size_t movesUndoneForFolds = 0;  ///< moves undone in the sweeps because they folded an element
  std::size_t nodesPutBackFolds = 0;    ///< moved nodes returned to their input position at the end: a fold there
  /// moved nodes returned to their input position at the end: beside a node put back, an element fell below
  /// min(the input's worst, worstGuard)
  std::size_t nodesPutBackGuard = 0;
  std::size_t freeNodes = 0, boundaryNodes = 0, featureNodes = 0, singularNodes = 0, userFixedNodes = 0;
  std::size_t creaseChains = 0;      ///< FeatureDetection::Creases: crease chains found
  std::string featureSummary;        ///< FeatureDetection::Creases: Creases::summary()
  std::size_t evaluations = 0;       ///< fitness evaluations (both methods)
  std::size_t nodesMoved = 0;
  std::size_t nodesPutBack = 0;      ///< moved nodes returned to their input position: the surface crossed itself there
  std::size_t searches = 0;          ///< node searches over all sweeps (the active set skips converged nodes)
  int sweeps = 0;
  int minPassSweeps = 0;             ///< final max-min sweeps run
  int colours = 0;
  double maxProjectionDistance = 0;  ///< largest candidate-to-surface distance of an accepted move
  double seconds = 0;
  double setupSeconds = 0;           ///< of which before the first sweep: checks, fixed nodes, C1 surface, colouring
};

/// Puts moved nodes back to their positions `before` until no two faces that cross (pectus::selfIntersections;
/// a quad is split along its diagonal v0-v2) and did not cross in `before` have a node that moved: a smoothed
/// surface must not cross itself where its input did not. `faces`: vertex indices into before/after (3 or 4
/// each). Returns the nodes put back, sorted; the input's own crossings are left as they are.
std::vector<int> restoreCrossings(const std::vector<std::vector<int>>& faces, const std::vector<Vec3>& before,
                                  std::vector<Vec3>& after);

/// Smooths with opt.method. Nodes are the live vertices of `m`. `userFixed` (per m.vert index, empty = none): 1 = keep fixed.
/// Moves that make the surface cross itself are undone at the end (restoreCrossings); a move that folds an
/// element (pectus/folds.h) that was not folded is undone in the sweep, and any fold left at the end by the
/// nodes put back is put back too, so the result has no fold its input did not have; so is any element that
/// the nodes put back leave below min(the input's worst, worstGuard).
/// Throws InputError for bad parameters, NaN coordinates or a mesh with no free node, TopologyError
/// (requireMesh, buildElements) for a mesh without faces, non-manifold input (edge or vertex) or invalid quads.
/// Fixed-node classes are counted once, in the order boundary, feature, singular, user.
Result smoothMesh(const CMeshO& m, const Options& opt, const std::vector<char>& userFixed = {});

}  // namespace pectus::smooth
