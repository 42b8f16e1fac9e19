// Import of a CT segmentation as users export it: surface files (STL binary/ASCII, OBJ, PLY, OFF) or
// NIfTI label maps (one multi-label file, or one mask file per structure as TotalSegmentator writes
// them), from one file or a folder. Host-free (no Qt): 'Pectus: Import CT Segmentation' maps it to layers.
#pragma once
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "pectus/cmesh.h"
#include "pectus/param_range.h"

namespace pectus::patient {

/// ImportOptions::minVoxels (importCt checks its lower end); the filter declares its parameter with it
inline constexpr ParamRange kMinVoxelsRange{0, 1000000000};

/// One imported structure: a layer of its own, named after the structure.
struct Structure {
  std::string name;         ///< file stem (mesh files, mask files) or the label table's name (label maps)
  std::string source;       ///< the file it came from
  int label = 0;            ///< the label value for a label map, else 0
  std::unique_ptr<OwnedMesh> mesh = std::make_unique<OwnedMesh>();
};

struct ImportOptions {
  /// label table for multi-label NIfTI files without one (value -> name lines: "1 rib_left_1", CSV
  /// "1,rib_left_1", or JSON {"1": "rib_left_1"}); empty: the file's own table, a sidecar
  /// <stem>.txt/.csv/.json or <stem>_labels.*, else TotalSegmentator's 'total' task table is NOT assumed.
  std::string labelTable;
  int minVoxels = 1;        ///< labels with fewer voxels are skipped (listed in the log)
};

struct ImportReport {
  std::vector<std::string> lines;   ///< what was read, one line per file or label (for the Log)
};

/// Reads one mesh file into `out` (cleared first). Throws IOError naming the file and the problem
/// (missing, unknown extension, unreadable), TopologyError when it has no faces.
void readMeshFile(const std::string& path, CMeshO& out);

/// What readMeshFile did besides reading. Vertices at the same position are merged (STL stores none
/// shared) and vertices no face uses are removed; faces with a NaN or infinite coordinate are dropped.
/// Everything else (duplicate or degenerate faces, holes, orientation) is kept as in the file.
struct MeshFileStats {
  std::string format;            ///< "binary STL", "ASCII STL", "OBJ", "PLY", "OFF"
  int trianglesRead = 0;         ///< triangles in the file (polygons fan-triangulated)
  int nonFiniteFaces = 0;        ///< dropped: a corner with a NaN or infinite coordinate
  int mergedVertices = 0;        ///< removed by merging with a vertex at the same position
  int unreferencedVertices = 0;  ///< removed: no face uses them
};
void readMeshFile(const std::string& path, CMeshO& out, MeshFileStats& stats);

/// The structure name of a file: its name without folder and without .nii.gz, .nii, .stl, .obj, .ply,
/// .off (any case): "/data/rib_left_3.nii.gz" -> "rib_left_3".
std::string structureName(const std::string& path);

/// A label table (value -> name) from text or from the file the text names. Entries are lines (or, in
/// text, ';'-separated): "1 rib_left_1", "1,rib_left_1", "1=rib_left_1", 3D Slicer colour-table lines
/// "1 rib_left_1 R G B A", ITK-SNAP lines with a quoted name, or one JSON object {"1": "rib_left_1"}
/// (also {"rib_left_1": 1}). '#' starts a comment line; a first line without a number is a header;
/// value 0 (background) is ignored. Throws InputError naming the line that cannot be read.
std::map<int, std::string> parseLabelTable(const std::string& textOrPath);

/// Connected components of a mesh's faces (faces sharing a vertex are connected).
int countComponents(const CMeshO& m);

/// "rib_left_3: 2,314 faces, 1,159 vertices, 1 component, from rib_left_3.stl" (a label map adds
/// " label 3").
std::string describe(const Structure& s);

/// A file (mesh or NIfTI) or a folder (every mesh and NIfTI file in it, sorted by name; other files are
/// skipped and listed). Structures come in file order, labels ascending. Throws IOError when the path is
/// missing, cannot be listed or holds no readable file, InputError when nothing can be imported from what
/// was read, naming the path and what was looked for.
std::vector<Structure> importSegmentation(const std::string& path, const ImportOptions& opt = {},
                                          ImportReport* report = nullptr,
                                          const std::function<void(int, const char*)>& progress = {});

}  // namespace pectus::patient
