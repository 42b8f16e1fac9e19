#include "pectus/fe/tetgen_mesher.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstring>

#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <tetgen.h>

#include "pectus/errors.h"
#include "pectus/grid_cell.h"
#include "pectus/self_intersections.h"

namespace pectus::fe {

using Eigen::Vector3d;

namespace {

struct Grid {
  Vector3d lo;
  double h = 1;
  int n[3] = {1, 1, 1};
  std::vector<std::vector<int>> cells;

  void build(const SurfaceMesh& s) {
    Eigen::AlignedBox3d box;
    for (const auto& v : s.V) box.extend(v);
    const Vector3d ext = box.sizes().cwiseMax(1e-9);
    const double vol = ext.prod();
    h = std::cbrt(vol / std::max<size_t>(1, s.F.size()));
    h = std::max(h, ext.maxCoeff() / 200.0);
    lo = box.min() - Vector3d::Constant(1e-6 * ext.maxCoeff());
    for (int d = 0; d < 3; ++d) n[d] = std::max(1, static_cast<int>(std::ceil((ext(d) + 2e-6 * ext.maxCoeff()) / h)));
    cells.assign(static_cast<size_t>(n[0]) * n[1] * n[2], {});
    for (int f = 0; f < static_cast<int>(s.F.size()); ++f) {
      int a[3], b[3];
      range(s, f, a, b);
      for (int k = a[2]; k <= b[2]; ++k)
        for (int j = a[1]; j <= b[1]; ++j)
          for (int i = a[0]; i <= b[0]; ++i) cells[idx(i, j, k)].push_back(f);
    }
  }
  int clampc(double x, int d) const { return clampedCell((x - lo(d)) / h, n[d]); }
  size_t idx(int i, int j, int k) const { return (static_cast<size_t>(k) * n[1] + j) * n[0] + i; }
  void range(const SurfaceMesh& s, int f, int a[3], int b[3]) const {
    for (int d = 0; d < 3; ++d) {
      double mn = 1e300, mx = -1e300;
      for (int v : s.F[f]) mn = std::min(mn, s.V[v](d)), mx = std::max(mx, s.V[v](d));
      a[d] = clampc(mn, d);
      b[d] = clampc(mx, d);
    }
  }
};

Vector3d closestOnTriangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  // Ericson, Real-Time Collision Detection 5.1.5
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double den = 1.0 / (va + vb + vc);
  return a + ab * (vb * den) + ac * (vc * den);
}

// The face of s nearest to p among those `skip` does not exclude, by shells of grid cells around p's cell
// (only their cells inside the grid: a shell costs its area, not the cube it bounds; iterating the cubes,
// a vertex of a flat 200 x 200 x 1 grid would cost ~1e9 cells, 10-120 s under ASan), and its squared
// distance (best2); -1 if there is none closer than `within` (mm; infinity: any face).
template <class Skip>
int nearestFace(const SurfaceMesh& s, const Grid& grid, const Vector3d& p, double within, const Skip& skip, double& best2) {
  int c[3];
  for (int d = 0; d < 3; ++d) c[d] = grid.clampc(p(d), d);
  best2 = std::numeric_limits<double>::infinity();
  int bestF = -1;
  auto visit = [&](int i, int j, int k) {
    for (int f : grid.cells[grid.idx(i, j, k)]) {
      if (skip(f)) continue;
      const auto& F = s.F[f];
      const double d = (closestOnTriangle(p, s.V[F[0]], s.V[F[1]], s.V[F[2]]) - p).squaredNorm();
      if (d < best2) best2 = d, bestF = f;
    }
  };
  int maxR = 0;  // beyond it the shell has no cell in the grid
  for (int d = 0; d < 3; ++d) maxR = std::max({maxR, c[d], grid.n[d] - 1 - c[d]});
  for (int r = 0; r <= maxR; ++r) {
    const int k0 = std::max(0, c[2] - r), k1 = std::min(grid.n[2] - 1, c[2] + r);
    const int j0 = std::max(0, c[1] - r), j1 = std::min(grid.n[1] - 1, c[1] + r);
    const int i0 = std::max(0, c[0] - r), i1 = std::min(grid.n[0] - 1, c[0] + r);
    for (int k = k0; k <= k1; ++k)
      for (int j = j0; j <= j1; ++j) {
        if (std::abs(k - c[2]) == r || std::abs(j - c[1]) == r) {  // a whole row of the shell
          for (int i = i0; i <= i1; ++i) visit(i, j, k);
        } else {  // the row crosses the inside: only its two ends are on the shell
          if (c[0] - r >= 0) visit(c[0] - r, j, k);
          if (r > 0 && c[0] + r < grid.n[0]) visit(c[0] + r, j, k);
        }
      }
    // every face not yet seen is at least r*h away from p (p lies inside its cell)
    if (r * grid.h >= std::min(std::sqrt(best2), within)) break;
  }
  return std::sqrt(best2) < within ? bestF : -1;
}

// A sentence on the surface's smallest feature when it is far below its edges (< 1e-3 of the median edge):
// what TetGen's failures on a closed, self-intersection-free surface come from (every such failure in the
// fuzz corpus has one); empty otherwise.
std::string smallFeatureHint(const SurfaceMesh& s) {
  const SurfaceFeature f = smallestFeature(s);
  if (!(f.size < 1e-3 * f.medianEdge) || f.vertex < 0) return {};
  std::ostringstream m;
  m.precision(3);
  m << " The surface's smallest feature, a likely cause: ";
  if (f.face < 0)
    m << "the edge between vertices " << f.vertex << " and " << f.other << " (at " << s.V[f.vertex].transpose()
      << " mm) is " << f.size << " mm long";
  else
    m << "vertex " << f.vertex << " (at " << s.V[f.vertex].transpose() << " mm) is " << f.size << " mm from face "
      << f.face << ", which it is not a corner of";
  m << ", against a median edge of " << f.medianEdge
    << " mm. Merge close vertices (Cleaning and Repairing > Merge Close Vertices) or remove the tiny faces there.";
  return m.str();
}

// What the mesher reads of TetGen's output: points (x, y, z) and linear tets (4 point indices each)
struct TetgenOutput {
  std::vector<double> points;
  std::vector<int> tets;
  int numPoints() const { return static_cast<int>(points.size() / 3); }
  int numTets() const { return static_cast<int>(tets.size() / 4); }
};

const char* const kTetgenAdvice = "check it is closed, not self-intersecting and without tiny features.";

// TetGen 1.6, on a surface it takes for self-intersecting, writes the faces it skipped into the working
// directory before it throws; a failed analysis leaves no such file behind (one that was there stays)
class SkippedFacesCleanup {
 public:
  SkippedFacesCleanup() {
    for (const char* f : kFiles) existed_.push_back(std::filesystem::exists(f));
  }
  void afterFailure() const {
    std::error_code ec;
    for (std::size_t i = 0; i < std::size(kFiles); ++i)
      if (!existed_[i]) std::filesystem::remove(kFiles[i], ec);
  }

 private:
  static constexpr const char* kFiles[] = {"tetgen-tmpfile_skipped.node", "tetgen-tmpfile_skipped.face"};
  std::vector<bool> existed_;
};

// TetGen's error code 3: "a self-intersection was detected"
constexpr int kTetgenSelfIntersection = 3;

// TetGen refused the surface with one of its error codes
class TetgenRefusal : public TopologyError {
 public:
  TetgenRefusal(int code, const std::string& msg) : TopologyError(msg), code_(code) {}
  int code() const { return code_; }

 private:
  int code_;
};

TetgenRefusal tetgenRefusal(int code) {
  return {code, "TetGen failed (error code " + std::to_string(code) + ") on the surface: " + kTetgenAdvice};
}

// TetGen in this process; its errors (thrown ints) become TetgenRefusal, a TopologyError
TetgenOutput tetgenHere(const std::string& switches, tetgenio& in) {
  tetgenio out;
  const SkippedFacesCleanup cleanup;
  try {
    ::tetrahedralize(const_cast<char*>(switches.c_str()), &in, &out);
  } catch (int code) {
    cleanup.afterFailure();
    throw tetgenRefusal(code);
  } catch (...) {
    cleanup.afterFailure();
    throw TopologyError(std::string("TetGen failed on the surface: ") + kTetgenAdvice);
  }
  TetgenOutput r;
  r.points.assign(out.pointlist, out.pointlist + 3 * std::max(0, out.numberofpoints));
  r.tets.resize(4 * std::size_t(std::max(0, out.numberoftetrahedra)));
  for (int t = 0; t < out.numberoftetrahedra; ++t)
    for (int k = 0; k < 4; ++k) r.tets[4 * std::size_t(t) + k] = out.tetrahedronlist[t * out.numberofcorners + k];
  return r;
}

bool writeAll(int fd, const void* data, std::size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w, n -= std::size_t(w);
  }
  return true;
}
// reads n bytes; false at end of file, on an error, or once `deadline` (if set) has passed
using Deadline = std::chrono::steady_clock::time_point;
bool readAll(int fd, void* data, std::size_t n, const Deadline* deadline, bool& timedOut) {
  char* p = static_cast<char*>(data);
  while (n > 0) {
    if (deadline) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(*deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return !(timedOut = true);
      pollfd pf{fd, POLLIN, 0};
      const int ready = ::poll(&pf, 1, static_cast<int>(std::min<long long>(left.count(), 1 << 30)));
      if (ready < 0 && errno == EINTR) continue;
      if (ready < 0) return false;
      if (ready == 0) return !(timedOut = true);
    }
    const ssize_t r = ::read(fd, p, n);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    p += r, n -= std::size_t(r);
  }
  return true;
}

// TetGen in a child process. Debian's TetGen 1.5 keeps its assertions, and on some valid-looking surfaces
// its Delaunay refinement stops on one (insertpoint: assert(0)) or crashes: in this
// process that would abort MeshLab with the user's unsaved work. The child (fork: a copy-on-write image of
// this one, only the calling thread) runs TetGen and sends the points and tets back through a pipe; a
// child that dies becomes a TopologyError, and so does one still running after `timeLimit` seconds (> 0),
// which is killed. Without fork (no memory for the page tables) TetGen runs here, without a time limit.
TetgenOutput runTetgen(const std::string& switches, tetgenio& in, double timeLimit) {
  constexpr int kRefusedStatus = 1000;  // the child's status for TetGen's error code c: kRefusedStatus + c
  int fd[2];
  if (::pipe(fd) != 0) return tetgenHere(switches, in);
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fd[0]), ::close(fd[1]);
    return tetgenHere(switches, in);
  }
  if (pid == 0) {  // child: status, message length, message or sizes and arrays; then _exit (no atexit, no destructors)
    ::close(fd[0]);
    // the host's crash handlers (MeshLab's, a fuzzer's, a sanitizer's) are not the child's: it just dies
    for (int sig : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL}) std::signal(sig, SIG_DFL);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // and it does not outlive its parent
    int status = 0;
    std::string msg;
    TetgenOutput r;
    try {
      r = tetgenHere(switches, in);
    } catch (const TetgenRefusal& e) {
      status = kRefusedStatus + e.code(), msg = e.what();
    } catch (const std::exception& e) {
      status = 1, msg = e.what();
    }
    const std::uint64_t len = msg.size(), np = r.points.size(), nt = r.tets.size();
    const bool ok = writeAll(fd[1], &status, sizeof status) && writeAll(fd[1], &len, sizeof len) &&
                    writeAll(fd[1], msg.data(), len) && writeAll(fd[1], &np, sizeof np) && writeAll(fd[1], &nt, sizeof nt) &&
                    writeAll(fd[1], r.points.data(), np * sizeof(double)) && writeAll(fd[1], r.tets.data(), nt * sizeof(int));
    ::_exit(ok ? 0 : 3);
  }
  ::close(fd[1]);
  const auto start = std::chrono::steady_clock::now();
  const Deadline deadline = start + std::chrono::milliseconds(static_cast<long long>(std::min(timeLimit, 1e9) * 1000));
  const Deadline* dl = timeLimit > 0 ? &deadline : nullptr;
  bool timedOut = false;
  auto get = [&](void* data, std::size_t n) { return readAll(fd[0], data, n, dl, timedOut); };
  int status = -1;
  std::uint64_t len = 0, np = 0, nt = 0;
  std::string msg;
  TetgenOutput r;
  bool ok = get(&status, sizeof status) && get(&len, sizeof len) && len < (1u << 20);
  if (ok) {
    msg.resize(len);
    ok = get(msg.data(), len) && get(&np, sizeof np) && get(&nt, sizeof nt) && np % 3 == 0 && nt % 4 == 0;
  }
  if (ok && status == 0) {
    r.points.resize(np);
    r.tets.resize(nt);
    ok = get(r.points.data(), np * sizeof(double)) && get(r.tets.data(), nt * sizeof(int));
  }
  ::close(fd[0]);
  if (timedOut) ::kill(pid, SIGKILL);
  int ws = 0;
  while (::waitpid(pid, &ws, 0) < 0 && errno == EINTR) {
  }
  if (timedOut) {
    std::ostringstream m;
    m << "TetGen did not finish within " << timeLimit << " s and was stopped: its quality refinement can go on "
      << "without end where the surface has tiny features, near-duplicate vertices or very sharp angles. "
      << "Merge close vertices, remove tiny faces, or mesh without quality refinement (tetQuality 0).";
    throw TopologyError(m.str());
  }
  if (WIFSIGNALED(ws)) {
    const int sig = WTERMSIG(ws);
    throw TopologyError(std::string("TetGen ") +
                     (sig == SIGABRT ? "stopped on one of its internal assertions" : "crashed (" + std::string(strsignal(sig)) + ")") +
                     " while meshing the surface (nothing else was affected): " + kTetgenAdvice +
                     " A different maximum tet volume or tet quality may also get past it.");
  }
  if (ok && status == 1) throw TopologyError(msg);  // tetgenHere failed on the surface in the child
  if (ok && status >= kRefusedStatus) throw TetgenRefusal(status - kRefusedStatus, msg);
  if (!ok || status != 0 || !WIFEXITED(ws) || WEXITSTATUS(ws) != 0)
    throw InputError("TetGen's process ended without a result (exit status " + std::to_string(WIFEXITED(ws) ? WEXITSTATUS(ws) : -1) + ").");
  return r;
}

/// New index of each TetGen output point such that surface vertex i is node i (the promise of
/// tetrahedralize) and the other points follow in TetGen's order. TetGen drops input points it does not
/// mesh (a point in no face outside the volume, a duplicate) and numbers the rest consecutively; it keeps
/// the coordinates of the points it keeps, so they are matched exactly. Throws InputError if a surface
/// vertex is not among them.
std::vector<int> inputVerticesFirst(const SurfaceMesh& s, const TetgenOutput& out) {
  const int nv = static_cast<int>(s.V.size()), np = out.numPoints();
  const double* pointlist = out.points.data();
  std::vector<int> node(np, -1);
  bool identity = np >= nv;
  for (int i = 0; i < nv && identity; ++i)
    for (int d = 0; d < 3; ++d) identity = identity && pointlist[3 * i + d] == s.V[i](d);
  if (identity) {
    std::iota(node.begin(), node.end(), 0);
    return node;
  }
  std::map<std::array<double, 3>, int> at;  // output point by its exact coordinates (the first of equal ones)
  for (int j = np - 1; j >= 0; --j) at[{pointlist[3 * j], pointlist[3 * j + 1], pointlist[3 * j + 2]}] = j;
  for (int i = 0; i < nv; ++i) {
    const auto it = at.find({s.V[i](0), s.V[i](1), s.V[i](2)});
    if (it == at.end() || node[it->second] >= 0) {
      std::ostringstream msg;
      msg << "TetGen left out surface vertex " << i << " (at " << s.V[i].transpose() << " mm): it coincides with "
          << (it == at.end() ? "another vertex" : "vertex " + std::to_string(node[it->second]))
          << " or lies outside the volume. Merge close vertices (e.g. MeshLab's 'Merge Close Vertices') and remove "
             "unreferenced ones.";
      throw TopologyError(msg.str());
    }
    node[it->second] = i;
  }
  int next = nv;
  for (int& n : node)
    if (n < 0) n = next++;
  return node;
}

}  // namespace

std::optional<std::pair<int, int>> findSelfIntersection(const SurfaceMesh& s) {
  const auto pairs = pectus::selfIntersections(s.V, s.F);
  if (pairs.empty()) return std::nullopt;
  return std::make_pair(pairs.front().a, pairs.front().b);
}

void checkSurfaceForTetgen(const SurfaceMesh& s) {
  const int nv = static_cast<int>(s.V.size());
  if (s.F.size() < 4) throw TopologyError("The surface has fewer than 4 triangles: it cannot bound a volume.");
  if (s.faceTissue.size() != s.F.size())
    throw InputError("The surface needs one tissue label per face (" + std::to_string(s.faceTissue.size()) + " labels for " +
                     std::to_string(s.F.size()) + " faces).");
  for (size_t f = 0; f < s.F.size(); ++f) {
    const auto& F = s.F[f];
    for (int i = 0; i < 3; ++i) {
      if (F[i] < 0 || F[i] >= nv) throw TopologyError("Face " + std::to_string(f) + " has an invalid vertex index.");
      if (F[i] == F[(i + 1) % 3]) throw TopologyError("Face " + std::to_string(f) + " is degenerate (repeated vertex).");
      if (s.faceTissue[f] <= 0) throw InputError("Face " + std::to_string(f) + " has no tissue label.");
    }
  }
  const Topology topo(s);
  for (const auto& e : topo.edges)
    if (e.faces != 2) {
      std::ostringstream m;
      m << "The surface is not closed: the edge between vertices " << e.a << " and " << e.b << " (at "
        << s.V[e.a].transpose() << ") belongs to " << e.faces
        << " face(s) instead of 2. Close the holes / remove non-manifold edges before meshing.";
      throw TopologyError(m.str());
    }
  if (auto p = findSelfIntersection(s)) {
    const auto& a = s.F[p->first];
    const Vector3d c = (s.V[a[0]] + s.V[a[1]] + s.V[a[2]]) / 3;
    std::ostringstream m;
    if (p->first == p->second)
      m << "Face " << p->first << " is degenerate: its three corners are collinear (near " << c.transpose()
        << " mm). Remove zero-area faces (Cleaning: Remove Zero Area Faces) before meshing.";
    else
      m << "The surface intersects itself: faces " << p->first << " and " << p->second << " cross (near " << c.transpose()
        << " mm). Remove the self-intersection (e.g. MeshLab's 'Select Self Intersecting Faces') before meshing.";
    throw TopologyError(m.str());
  }
}

std::vector<int> nearestFaces(const SurfaceMesh& s, const std::vector<Vector3d>& pts) {
  Grid grid;
  grid.build(s);
  std::vector<int> out(pts.size(), -1);
#pragma omp parallel for schedule(dynamic, 64)
  for (long q = 0; q < static_cast<long>(pts.size()); ++q) {
    double best2 = 0;
    out[q] = nearestFace(s, grid, pts[q], std::numeric_limits<double>::infinity(), [](int) { return false; }, best2);
  }
  return out;
}

SurfaceFeature smallestFeature(const SurfaceMesh& s) {
  SurfaceFeature r;
  const int nv = static_cast<int>(s.V.size());
  std::vector<double> lengths;
  lengths.reserve(3 * s.F.size());
  for (const auto& F : s.F)
    for (int i = 0; i < 3; ++i) {
      const int a = F[i], b = F[(i + 1) % 3];
      if (a < 0 || b < 0 || a >= nv || b >= nv) continue;
      const double l = (s.V[a] - s.V[b]).norm();
      lengths.push_back(l);
      if (l < r.size) r.size = l, r.vertex = std::min(a, b), r.other = std::max(a, b), r.face = -1;
    }
  if (lengths.empty()) return r;
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  r.medianEdge = lengths[lengths.size() / 2];
  std::vector<std::vector<int>> facesOf(static_cast<size_t>(nv));
  for (int f = 0; f < static_cast<int>(s.F.size()); ++f)
    for (int v : s.F[f])
      if (v >= 0 && v < nv) facesOf[v].push_back(f);
  Grid grid;
  grid.build(s);
  for (int v = 0; v < nv; ++v) {
    if (facesOf[v].empty()) continue;
    const auto& own = facesOf[v];
    double best2 = 0;
    const int f = nearestFace(s, grid, s.V[v], r.size, [&](int g) { return std::find(own.begin(), own.end(), g) != own.end(); }, best2);
    if (f >= 0 && std::sqrt(best2) < r.size) r.size = std::sqrt(best2), r.vertex = v, r.other = -1, r.face = f;
  }
  return r;
}

namespace {

// the surface as TetGen's input: its points, and one facet per triangle marked with the face's tissue
void fillTetgenInput(const SurfaceMesh& s, tetgenio& in) {
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(s.V.size());
  in.pointlist = new REAL[3 * s.V.size()];
  for (size_t i = 0; i < s.V.size(); ++i)
    for (int d = 0; d < 3; ++d) in.pointlist[3 * i + d] = s.V[i](d);
  in.numberoffacets = static_cast<int>(s.F.size());
  in.facetlist = new tetgenio::facet[s.F.size()];
  in.facetmarkerlist = new int[s.F.size()];
  for (size_t f = 0; f < s.F.size(); ++f) {
    tetgenio::facet& fc = in.facetlist[f];
    tetgenio::init(&fc);
    fc.numberofpolygons = 1;
    fc.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&fc.polygonlist[0]);
    fc.polygonlist[0].numberofvertices = 3;
    fc.polygonlist[0].vertexlist = new int[3];
    for (int k = 0; k < 3; ++k) fc.polygonlist[0].vertexlist[k] = s.F[f][k];
    in.facetmarkerlist[f] = s.faceTissue[f];
  }
}

// TetGen's switches for the options
std::string tetgenSwitches(const TetgenOptions& opt) {
  std::ostringstream sw;
  sw << "pzQ";
  if (opt.preserveSurface) sw << "Y";
  if (opt.radiusEdgeRatio > 0) sw << "q" << opt.radiusEdgeRatio;
  if (opt.maxVolume > 0) sw << "a" << opt.maxVolume;
  if (opt.maxAddedPoints >= 0) sw << "S" << opt.maxAddedPoints;
  return sw.str();
}

// TetGen 1.6 merges adjacent facets of one tissue where they are nearly coplanar (or where a sliver face
// has a small angle beside a nearly flat edge) and triangulates the merged facet anew; on a surface the exact
// check has found free of self-intersections, that new triangulation can cross a neighbour and TetGen
// refuses its own result as self-intersecting. Meshed again without merging (-M), the input triangles are
// kept as they are. Surfaces TetGen meshes at the first attempt (every one with TetGen 1.5) are unchanged.
TetgenOutput meshSurface(const std::string& switches, tetgenio& in, const TetgenOptions& opt) {
  TetgenOutput out;
  try {
    out = runTetgen(switches, in, opt.timeLimitSeconds);
  } catch (const TetgenRefusal& e) {
    if (e.code() != kTetgenSelfIntersection) throw;
    out = runTetgen(switches + "M", in, opt.timeLimitSeconds);
  }
  if (out.numTets() <= 0) throw TopologyError("TetGen produced no tetrahedra (is the surface closed?).");
  for (int v : out.tets)
    if (v < 0 || v >= out.numPoints()) throw InputError("TetGen returned a tetrahedron with a node out of range.");
  return out;
}

// TetGen's tets as a TET4 mesh, the surface's vertices first and every tet positively oriented (a tet
// without volume is an error); marks in inTet the surface vertices the tets use, gives the tets' centroids
TetMesh linearMesh(const SurfaceMesh& s, const TetgenOutput& out, std::vector<char>& inTet, std::vector<Vector3d>& centroids) {
  const std::vector<int> node = inputVerticesFirst(s, out);
  TetMesh m;
  m.order = 1;
  m.nodes.resize(out.numPoints());
  for (int i = 0; i < out.numPoints(); ++i)
    m.nodes[node[i]] = Vector3d(out.points[3 * i], out.points[3 * i + 1], out.points[3 * i + 2]);
  m.tets.resize(out.numTets());
  centroids.resize(out.numTets());
  inTet.assign(s.V.size(), 0);
  for (int t = 0; t < out.numTets(); ++t) {
    std::array<int, 10> e{};
    for (int k = 0; k < 4; ++k) {
      e[k] = node[out.tets[4 * std::size_t(t) + k]];
      if (e[k] < static_cast<int>(inTet.size())) inTet[e[k]] = 1;
    }
    m.tets[t] = e;
    if (m.tetVolume(t) < 0) std::swap(m.tets[t][1], m.tets[t][2]);
    if (!(m.tetVolume(t) > 0)) {  // flat in double precision (TetGen's exact predicates saw a volume): no stiffness
      std::ostringstream msg;
      msg << "TetGen made a tetrahedron without volume (tet " << t << ", near " << m.centroid(t).transpose()
          << " mm): the surface has features far smaller than its tets (near-duplicate vertices, tiny faces). Merge "
             "close vertices, remove tiny faces, or change the maximum tet volume or the tet quality.";
      throw TopologyError(msg.str());
    }
    centroids[t] = m.centroid(t);
  }
  return m;
}

// every surface vertex must be a node of some tet
void requireEveryVertexMeshed(const SurfaceMesh& s, const std::vector<char>& inTet) {
  for (size_t i = 0; i < inTet.size(); ++i)
    if (!inTet[i]) {
      std::ostringstream msg;
      msg << "Surface vertex " << i << " (at " << s.V[i].transpose() << " mm) is in no tetrahedron: it lies outside "
          << "the meshed volume. Remove it (e.g. MeshLab's 'Remove Unreferenced Vertices').";
      throw TopologyError(msg.str());
    }
}

// tetrahedralize after its checks
TetMesh tetgenMesh(const SurfaceMesh& s, const TetgenOptions& opt, std::vector<int>* tetFace) {
  tetgenio in;
  fillTetgenInput(s, in);
  const TetgenOutput out = meshSurface(tetgenSwitches(opt), in, opt);
  std::vector<char> inTet;
  std::vector<Vector3d> centroids;
  TetMesh m = linearMesh(s, out, inTet, centroids);
  requireEveryVertexMeshed(s, inTet);
  const std::vector<int> nf = nearestFaces(s, centroids);
  m.tissue.resize(m.tets.size());
  for (size_t t = 0; t < m.tets.size(); ++t) m.tissue[t] = s.faceTissue[nf[t]];
  if (tetFace) *tetFace = nf;
  return opt.order == 2 ? toQuadratic(m) : m;
}
}  // namespace

void validate(const TetgenOptions& opt) {
  if (opt.order != 1 && opt.order != 2) throw InputError("Element order must be 1 (TET4) or 2 (TET10).");
  if (!std::isfinite(opt.radiusEdgeRatio) || (opt.radiusEdgeRatio > 0 && opt.radiusEdgeRatio < kMinRadiusEdgeRatio)) {
    std::ostringstream s;
    s << "The tet quality (TetGen's radius-edge bound) must be 0 (no refinement) or at least " << kMinRadiusEdgeRatio
      << ": TetGen does not terminate below; got " << opt.radiusEdgeRatio << ".";
    throw InputError(s.str());
  }
  if (!std::isfinite(opt.maxVolume)) throw InputError("The maximum tet volume must be a number (mm^3; 0: no limit).");
}

TetMesh tetrahedralize(const SurfaceMesh& s, const TetgenOptions& opt, std::vector<int>* tetFace) {
  validate(opt);
  checkSurfaceForTetgen(s);
  try {
    return tetgenMesh(s, opt, tetFace);
  } catch (const TopologyError& e) {  // TetGen failed: say where the surface's features are tiny, if they are
    throw TopologyError(e.what() + smallFeatureHint(s));
  } catch (const InputError& e) {  // any other failure keeps its kind and gets the same hint
    throw InputError(e.what() + smallFeatureHint(s));
  }
}

}  // namespace pectus::fe
