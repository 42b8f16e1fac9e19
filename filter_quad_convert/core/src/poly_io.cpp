#include "pectus/quad/poly_io.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "pectus/errors.h"

namespace pectus::quad {

void writePolyMesh(const std::string& path, const PolyMesh& m, PolyFormat format) {
  if (path.empty()) throw IOError("no output file name was given");
  std::FILE* fh = std::fopen(path.c_str(), "w");
  if (!fh)
    throw IOError("cannot write '" + path + "': " + std::strerror(errno) +
                     " (check that the folder exists and is writable)");
  const auto vertices = [&](const char* prefix) {
    for (const auto& p : m.V) std::fprintf(fh, "%s%.9g %.9g %.9g\n", prefix, p.x(), p.y(), p.z());
  };
  std::size_t indices = 0;
  for (const auto& f : m.F) indices += 1 + f.nv;
  switch (format) {
    case PolyFormat::OBJ:
      std::fprintf(fh, "# pectus-meshlab: %zu quads, %zu triangles\n", m.quads(), m.triangles());
      vertices("v ");
      for (const auto& f : m.F) {
        std::fputc('f', fh);
        for (int k = 0; k < f.nv; ++k) std::fprintf(fh, " %d", f.v[k] + 1);
        std::fputc('\n', fh);
      }
      break;
    case PolyFormat::OFF:
      std::fprintf(fh, "OFF\n%zu %zu 0\n", m.V.size(), m.F.size());
      vertices("");
      for (const auto& f : m.F) {
        std::fprintf(fh, "%d", f.nv);
        for (int k = 0; k < f.nv; ++k) std::fprintf(fh, " %d", f.v[k]);
        std::fputc('\n', fh);
      }
      break;
    case PolyFormat::VTK:
      std::fprintf(fh, "# vtk DataFile Version 3.0\npectus-meshlab quad mesh\nASCII\nDATASET POLYDATA\n");
      std::fprintf(fh, "POINTS %zu double\n", m.V.size());
      vertices("");
      std::fprintf(fh, "POLYGONS %zu %zu\n", m.F.size(), indices);
      for (const auto& f : m.F) {
        std::fprintf(fh, "%d", f.nv);
        for (int k = 0; k < f.nv; ++k) std::fprintf(fh, " %d", f.v[k]);
        std::fputc('\n', fh);
      }
      break;
  }
  const bool bad = std::ferror(fh) != 0;
  if (std::fclose(fh) != 0 || bad) throw IOError("writing '" + path + "' failed (disk full?)");
}

}  // namespace pectus::quad
