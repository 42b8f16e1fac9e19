// A patient's rib cage from a CT segmentation, made ready for the analyses: the structures classified, put in
// the project's frame, made solids on one grid, separated, numbered, joined into one labelled surface, and
// landmarked.
// Host-free (vcglib + Eigen + CGAL, no Qt): 'Pectus: Prepare Patient Rib Cage' maps it to layers.
//
// The steps, in order (each one Logged):
//  1. classify every layer by its name (TotalSegmentator's, 3D Slicer's, or generic names): rib (side
//     and number), costal cartilage, sternum, vertebra, other bone (may hold ribs fused to the spine),
//     or not rib cage (scapula, clavicle, humerus, organs: left out); layers whose names say nothing
//     ('Segment_1', ...) by their shape and place among the others, in the input's own frame and units
//     (shape_classify.h): many long pieces or one piece as wide as the cage -> bone; many small bars ->
//     cartilage; the elongated one-piece layer nearest the cartilages -> sternum; then, in the axes the
//     sternum gives, compact midline blocks behind the centre -> vertebrae, thin elongated pieces beside
//     the midline reaching behind the centre -> ribs (side and number from step 5), plates behind and
//     beside -> scapulae (left out), the rest left out; no cartilage or sternum by name or shape, or two
//     equally good sternums: refused, asking to rename the layers;
//  2. units: metres or centimetres are detected from the size of the whole and scaled to mm;
//  3. the anatomical frame: anterior from the bone's centre to the sternum, the long axis along the
//     sternum, snapped to the file's axes when within 30 degrees (CT exports are axis-aligned), superior
//     where the cage is narrow, the patient's left from the right-handed scanner frame (or from the names);
//  4. every structure becomes a solid on one grid (solid_grid.h; step PrepareOptions::gridStep, in the frame's
//     axes): the grid points that cannot be reached from outside without crossing its faces. Holes are capped
//     first (a fan over each rim) and faces written twice ignored; self-intersections, nested (marrow) shells,
//     slivers and fused neighbours then change nothing, and no structure is refused for its geometry. In the
//     grid: the sternum's gaps along its length (up to 4 mm: manubrium and body apart) are bridged; pieces
//     under the minimum volume are fragments, dropped; a bone layer's vertebral column (the bone thicker than
//     a rib, where a 4 mm ball fits, on the posterior midline) is cut away at the costovertebral joints, the
//     ribs' ends square 1.5 mm beyond it (a sheet thinner than 2.4 mm that a rib running along the cut leaves
//     there goes with it); of the rest, pieces that do not reach the cut (scapulae, clavicles, loose bone) and
//     pieces shorter than a quarter of the longest (split-off processes, cut fragments) are left out, each
//     Logged.
//     The column (the cut-away bone and the vertebra layers) is left out of the model, as the thesis does, or
//     kept as the fixed support (PrepareOptions::spine): tissue bone, part kVertebralColumn (400);
//  5. ribs are numbered per side from the top by the height of their vertebral end (or from their names);
//  6. the structures' grid points give one surface (marching cubes; between grid points it follows the input's
//     faces): closed, 2-manifold and embedded by construction, each face with the tissue and part of the
//     structure nearest to it (a cartilage face: the nearest rib's part); where structures overlap, the
//     sternum keeps the point, then the ribs, the cartilages, the column. Its connected pieces are Logged,
//     then it is decimated to the target edge length (kept embedded) and relabelled;
//  7. landmarks (labels.h codes) are placed from the anatomy, on the full-detail surface without the column
//     (the same whatever the edge length and the spine mode); user points override them. A landmark that
//     cannot be placed is refused naming it and its code (pick it: .pp file), unless the user gives it.
// Every step is deterministic: the same layers give the same cage, byte for byte, on any thread count.
// The result is in the project frame (labels.h): mm, +x patient's left, +y anterior, +z superior, x = 0 on
// the sternum's midline, y = 0 at the vertebral bodies' anterior surface (else at the costovertebral
// joints), z = 0 half a rib level below the lowest costovertebral joint.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "pectus/cmesh.h"
#include "pectus/errors.h"
#include "pectus/labels.h"
#include "pectus/param_range.h"

namespace pectus::patient {

// Valid ranges of PrepareOptions (preparePatientCage checks them); 'Pectus: Prepare Patient Rib Cage' declares its
// parameters with the same constants.
inline constexpr ParamRange kMinVolumeRange{0, 100000};  ///< PrepareOptions::minVolume (mm^3)
inline constexpr ParamRange kGridStepRange{0.3, 3};      ///< PrepareOptions::gridStep (mm)
/// PrepareOptions::edgeLength (mm): 0 keeps every face, else at least kMinEdgeLength
inline constexpr ParamRange kEdgeLengthRange{0, 10};
inline constexpr double kMinEdgeLength = 0.5;

/// What a layer holds, from its name.
enum class Kind { Rib, Cartilage, Sternum, Vertebra, Bone, NotCage, Unknown };
struct NameClass {
  Kind kind = Kind::Unknown;
  int side = 0;  ///< 1 right, 2 left, 0 unknown
  int number = 0;  ///< rib (or cartilage) number, 0 unknown
};
/// Classifies a structure name (case-insensitive; '_', '-', ' ' and '.' separate words): 'rib_left_3',
/// 'Rib R 3', 'left rib 3' -> rib; 'costal_cartilages', 'cartilage_left_5' -> cartilage; 'sternum',
/// 'manubrium', 'xiphoid' -> sternum; 'vertebrae_T5', 'spine' -> vertebra; 'bone', 'ribs', 'skeleton' ->
/// bone; 'scapula_left', 'clavicula_*', 'humerus_*' and every other class TotalSegmentator writes (organs,
/// vessels, muscles: 'colon', 'pancreas', 'spinal_cord', ...) -> not cage; other names ('Segment_1') -> unknown
/// (the layer is classified by its shape).
NameClass classifyName(const std::string& name);

struct InputLayer {
  std::string name;
  const CMeshO* mesh = nullptr;
};

enum class Units { Auto, Millimetres, Centimetres, Metres };
/// The vertebral column: cut away at the costovertebral joints (the thesis: the joints are the fixed
/// support), or kept in the model as the fixed support (tissue bone, part kVertebralColumn; the FE
/// analysis fixes all its nodes). Landmarks are the same either way.
enum class SpineMode { Cut, Keep };
enum class FrameMode { Auto, RAS, LPS, Model };

struct PrepareOptions {
  Units units = Units::Auto;
  FrameMode frame = FrameMode::Auto;
  double minVolume = 200;    ///< mm^3: smaller connected pieces are fragments, dropped
  /// mm: the step of the grid on which every structure becomes a solid (about a CT's voxel). Features thinner
  /// than a step may close up or vanish; the surface between grid points follows the input's faces
  double gridStep = 0.8;
  /// mm: the joined surface is decimated to this edge length (0: kept as is). The FE analysis' cost grows
  /// with its cube: 4 mm gives about 100,000 tets for a child's cage (2 mm: about 480,000)
  double edgeLength = 4.0;
  SpineMode spine = SpineMode::Cut;
  /// user landmarks in the INPUT layers' frame and units (picked points); each replaces the automatic
  /// landmark of its code
  std::vector<Landmark> userLandmarks;
};

struct PrepareResult {
  std::vector<Landmark> landmarks;        ///< in the project frame
  Eigen::Matrix4d inputToModel = Eigen::Matrix4d::Identity();  ///< input layer coordinates -> result (mm)
  std::vector<std::string> log;           ///< every decision, one line each
  int ribsRight = 0, ribsLeft = 0, dropped = 0;
  double seconds = 0;
};

/// Builds the labelled cage into `cage` (cleared first; face labels by writeFaceLabels). Throws InputError
/// naming what to fix, only for missing anatomy or settings: an option outside its range above, no sternum, no
/// cartilage, ribs on one side only, ribs missing, nothing recognised by name or shape (rename the layers), a
/// frame that cannot be found, a landmark that cannot be placed and is not given.
PrepareResult preparePatientCage(const std::vector<InputLayer>& layers, const PrepareOptions& opt, CMeshO& cage,
                                 const std::function<void(int, const char*)>& progress = {});

/// What preparePatientCage throws for an InputError: the same message, and the decisions made before it (what
/// each layer was taken for, what was left out and why, the rib numbering), so that the user can rename a layer
/// or pick a point and try again
class PrepareRefusal : public InputError {
 public:
  PrepareRefusal(const std::string& what, std::vector<std::string> decisions) : InputError(what), log(std::move(decisions)) {}
  std::vector<std::string> log;
};

/// Points picked with MeshLab's PickPoints tool (a .pp file: <point x=".." y=".." z=".." name=".." active="1"/>)
/// as landmarks: the name is the code ("500") or starts with it ("500 lower sternum end"); inactive points
/// and names without a code are skipped (counted in `skipped`). Throws IOError if the file is unreadable.
std::vector<Landmark> readPickedPoints(const std::string& path, int* skipped = nullptr);

}  // namespace pectus::patient
