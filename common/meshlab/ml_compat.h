// The one place where MeshLab's two plugin APIs differ for this project:
//  - 2020.09 (Debian bookworm): MeshFilterInterface, bool applyFilter + errorMessage, RichMesh holding a
//    MeshModel*, MeshDocument::meshList;
//  - 2021.05 and later (2022.02 in trixie, 2025.07 in forky, pymeshlab): FilterPlugin, applyFilter
//    returning a result map and throwing MLException, a const document in initParameterList, RichMesh
//    holding a mesh id, meshIterator(), renamed parameter classes, CMeshO's members out of line in
//    libmeshlab-common.
// CMake defines PECTUS_MESHLAB_API (2020 or 2021) from the headers it is given. Plugins use the names
// below and never test the version themselves.
#pragma once
#include <QObject>

#if PECTUS_MESHLAB_API >= 2021
#include <common/globals.h>
#include <common/mlexception.h>
#include <common/plugins/interfaces/filter_plugin.h>
#include <common/parameters/rich_parameter_list.h>
#if __has_include(<common/parameters/rich_parameters.h>)
#include <common/parameters/rich_parameters.h>
#else  // 2021.05-2022.02: every parameter class in one header
#include <common/parameters/rich_parameter.h>
#endif
#else
#include <common/interfaces.h>
#endif

#include <string>
#include <vector>

#if PECTUS_MESHLAB_API >= 2021
#ifndef MESHLAB_VERSION
#error "MESHLAB_VERSION must be defined (the MeshLab release the plugins load into, e.g. 2025.07)"
#endif
// The plugin metadata a filter plugin class declares right after Q_OBJECT (moc expands it).
#define PECTUS_FILTER_PLUGIN_METADATA \
  MESHLAB_PLUGIN_IID_EXPORTER(FILTER_PLUGIN_IID) \
  Q_INTERFACES(FilterPlugin)
#else
#define PECTUS_FILTER_PLUGIN_METADATA \
  MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID) \
  Q_INTERFACES(MeshFilterInterface)
#endif

#if PECTUS_MESHLAB_API >= 2021
// 2025.07 renamed these parameter classes (2021.05-2022.02 had the 2020.09 names, and RichPosition);
// the .mlx type names stay RichPoint3f/RichPosition, RichSaveFile, RichOpenFile, RichAbsPerc.
#if __has_include(<common/parameters/rich_parameter/rich_file_save.h>)
using RichSaveFile = RichFileSave;
using RichOpenFile = RichFileOpen;
using RichAbsPerc = RichPercentage;
#endif
using RichPoint3f = RichPosition;
#endif

namespace pectus::ml {

#if PECTUS_MESHLAB_API >= 2021
using HostFilter = FilterPlugin;
using FilterClass = FilterPlugin::FilterClass;
using FilterArity = FilterPlugin::FilterArity;
/// the type MeshLab passes an action as to the plugin's per-action queries
using ActionPtr = const QAction*;
#else
using HostFilter = MeshFilterInterface;
using FilterClass = MeshFilterInterface::FilterClass;
using FilterArity = MeshFilterInterface::FILTER_ARITY;
using ActionPtr = QAction*;
#endif

/// The MeshLab release the plugins were built for ("2020.09", "2025.07").
const char* hostVersion();

/// Every layer of the document, in order. The pointers stay valid while the layer exists; a const
/// document still hands out mutable layers because RichMesh defaults are taken from it.
std::vector<MeshModel*> meshes(const MeshDocument& md);
/// The current layer, or nullptr.
MeshModel* currentMesh(const MeshDocument& md);
/// Removes a layer (a layer this filter added and must take back).
void removeLayer(MeshDocument& md, MeshModel* m);
/// A layer-choice parameter whose default is `def` (may be nullptr: the first layer).
RichMesh richMesh(const QString& name, MeshModel* def, const MeshDocument& md, const QString& desc,
                  const QString& help);
/// The number a script gives a layer in a RichMesh value: its position (2020.09), its id (2021.05 and later).
int layerNumber(const MeshDocument& md, const MeshModel& m);
/// The layer a RichMesh parameter names, or nullptr if it names none.
MeshModel* meshParam(const RichParameterList& par, MeshDocument& md, const QString& name);
/// Bounding box and normals after the coordinates changed.
void updateBoxAndNormals(MeshModel& m);

}  // namespace pectus::ml
