// Import of a CT segmentation as users export it: surface files (STL binary/ASCII, OBJ, PLY, OFF) or
// NIfTI label maps (one multi-label file, or one mask file per structure as TotalSegmentator writes
// them), from one file or a folder. Host-free (no Qt): 'Import CT Segmentation' maps it to layers.
#pragma once
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "pectus/cmesh.h"

namespace pectus::patient {

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

/// Reads one mesh file into `out` (cleared first). Throws InputError naming the file and the problem
/// (missing, unknown extension, unreadable, no faces).
void readMeshFile(const std::string& path, CMeshO& out);

/// A file (mesh or NIfTI) or a folder (every mesh and NIfTI file in it, sorted by name; other files are
/// skipped and listed). Structures come in file order, labels ascending. Throws InputError when nothing
/// can be read, naming the path and what was looked for.
std::vector<Structure> importSegmentation(const std::string& path, const ImportOptions& opt = {},
                                          ImportReport* report = nullptr,
                                          const std::function<void(int, const char*)>& progress = {});

}  // namespace pectus::patient
