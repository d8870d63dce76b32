// The only translation unit that includes CGAL (its skin-surface headers take a minute to compile).
#include "clump/UnionOfBalls.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polyhedron_3.h>
#include <CGAL/Skin_surface_traits_3.h>
#include <CGAL/Union_of_balls_3.h>
#include <CGAL/mesh_union_of_balls_3.h>
#include <CGAL/subdivide_union_of_balls_mesh_3.h>

#include <algorithm>
#include <cmath>
#include <list>

namespace trueaniso {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Union = CGAL::Union_of_balls_3<CGAL::Skin_surface_traits_3<Kernel>>;
using Mesh = CGAL::Polyhedron_3<Kernel>;
constexpr Real kPi = 3.14159265358979323846;

struct Moments {
  Real V = 0;
  Vec3 S = Vec3::Zero();
  Mat3 J = Mat3::Zero();
};

// Sum over the outward triangles (a, b, c) of the tetrahedron (0, a, b, c): volume a.(b x c)/6,
// first moment V (a+b+c)/4, second moment V/20 (a a^T + b b^T + c c^T + s s^T) with s = a+b+c.
Moments meshMoments(const Mesh& mesh) {
  Moments m;
  for (auto f = mesh.facets_begin(); f != mesh.facets_end(); ++f) {
    auto h = f->halfedge();
    auto at = [](const Kernel::Point_3& p) { return Vec3(p.x(), p.y(), p.z()); };
    const Vec3 a = at(h->vertex()->point()), b = at(h->next()->vertex()->point()),
               c = at(h->next()->next()->vertex()->point());
    const Real v = a.dot(b.cross(c)) / 6.0;
    const Vec3 s = a + b + c;
    m.V += v;
    m.S += (v / 4.0) * s;
    m.J += (v / 20.0) * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
  }
  return m;
}

Moments richardson(const Moments& coarse, const Moments& fine) {  // error ~ h^2, h halves
  return Moments{fine.V + (fine.V - coarse.V) / 3.0, fine.S + (fine.S - coarse.S) / 3.0,
                 fine.J + (fine.J - coarse.J) / 3.0};
}

}  // namespace

UnionMoments unionOfBallsMoments(const std::vector<Vec3>& centres, const std::vector<Real>& radii, int levels) {
  require(!centres.empty() && centres.size() == radii.size(), "union of balls: as many centres as radii, >= 1");
  require(levels >= 2 && levels <= 7, "union of balls: subdivision levels must lie in [2, 7]");
  UnionMoments out;
  if (centres.size() == 1) {
    const Real r = radii[0], V = 4.0 / 3.0 * kPi * r * r * r;
    out.volume = V;
    out.first = V * centres[0];
    out.second = V * centres[0] * centres[0].transpose() + Mat3::Identity() * (V * r * r / 5.0);
    return out;
  }
  // The mesh is built about the members' mean centre and in units of the largest radius: CGAL's
  // skin-surface mesher is not scale-free (at radii of 1e-4 m its volume came out 16 % wrong),
  // and the round-off of the sums stays small.
  Vec3 origin = Vec3::Zero();
  for (const Vec3& c : centres) origin += c;
  origin /= static_cast<Real>(centres.size());
  const Real unit = *std::max_element(radii.begin(), radii.end());
  std::list<Kernel::Weighted_point_3> balls;
  for (size_t i = 0; i < centres.size(); ++i) {
    const Vec3 c = (centres[i] - origin) / unit;
    const Real r = radii[i] / unit;
    balls.emplace_back(Kernel::Point_3(c.x(), c.y(), c.z()), r * r);  // weight = r^2
  }
  const Union uni(balls.begin(), balls.end());
  Mesh mesh;
  CGAL::mesh_union_of_balls_3(uni, mesh);
  Moments level[3];  // levels L-2, L-1, L
  for (int k = 0; k <= levels; ++k) {
    if (k > 0) CGAL::subdivide_union_of_balls_mesh_3(uni, mesh, 1);
    if (k >= levels - 2) level[k - (levels - 2)] = meshMoments(mesh);
  }
  const Moments prev = richardson(level[0], level[1]);
  Moments unitBest = richardson(level[1], level[2]);
  // CGAL's mesher walks its facets in an order that depends on the process's memory layout, so the
  // sums above differ in their last bits between processes (two template bit patterns seen for one
  // shape), and a clump preparation, being chaotic, then ends in another packing. Rounding the
  // moments to 2^-36 of the volume (1.5e-11, a million times below the method's 1e-5 accuracy)
  // makes them the same in every process; a last-bit difference moves a value across a rounding
  // boundary with probability 2^-16.
  const auto fixed = [quantum = std::ldexp(1.0, std::ilogb(unitBest.V) - 36)](Real x) {
    return std::round(x / quantum) * quantum;
  };
  unitBest.V = fixed(unitBest.V);
  unitBest.S = unitBest.S.unaryExpr(fixed);
  unitBest.J = unitBest.J.unaryExpr(fixed);
  // Back to the input frame: x = unit y + origin.
  const Real u3 = unit * unit * unit;
  const Real V = u3 * unitBest.V;
  const Vec3 S = u3 * unit * unitBest.S;
  const Mat3 J = u3 * unit * unit * unitBest.J;
  out.volume = V;
  out.first = S + V * origin;
  out.second = J + S * origin.transpose() + origin * S.transpose() + V * origin * origin.transpose();
  // The coarser level's volume rounded alike: unrounded, the estimate (written into every clump
  // specimen's metadata) would differ in its last bits between identical runs.
  out.volumeErrorEstimate = std::abs(unitBest.V - fixed(prev.V)) / unitBest.V;
  out.facets = static_cast<long>(mesh.size_of_facets());
  return out;
}

}  // namespace trueaniso
