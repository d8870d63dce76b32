// Clump templates as seen from Python: built from member centres and radii (validated and computed
// in C++, engines/clump), and placed in a scene in bulk.
#include <memory>

#include "clump/ClumpTemplate.hpp"
#include "core/Scene.hpp"
#include "python/Numpy.hpp"

namespace trueaniso::py {

namespace {

using TemplatePtr = std::shared_ptr<ClumpTemplate>;

TemplatePtr makeTemplate(const bp::object& centres, const bp::object& radii, int levels) {
  return std::make_shared<ClumpTemplate>(
      makeClumpTemplate(toVec3List(centres, "member centres"), toRealList(radii, "member radii"), levels));
}

np::ndarray offsets(const ClumpTemplate& t) { return toNumpy(t.offsets); }
np::ndarray radii(const ClumpTemplate& t) { return toNumpy(t.radii); }
np::ndarray inertia(const ClumpTemplate& t) { return toNumpy(t.inertia); }
np::ndarray centroid(const ClumpTemplate& t) { return toNumpy(t.centroid); }
np::ndarray axes(const ClumpTemplate& t) { return toNumpy(t.axes); }
TemplatePtr scaled(const ClumpTemplate& t, Real f) { return std::make_shared<ClumpTemplate>(t.scaled(f)); }

// Clumps of one template: positions (n, 3), orientations (n, 4) as (w, x, y, z), scales (n).
// Everything is checked before the first clump is added.
void addClumps(Scene& s, const ClumpTemplate& t, const bp::object& pos, const bp::object& quat,
               const bp::object& scales) {
  const std::vector<Vec3> p = toVec3List(pos, "positions");
  const std::vector<Real> q = toRealList(bp::import("numpy").attr("ravel")(quat), "orientations");
  const std::vector<Real> f = toRealList(scales, "scales");
  require(q.size() == 4 * p.size() && f.size() == p.size(),
          "add_clumps: positions (n, 3), orientations (n, 4) and scales (n) must describe the same n clumps");
  for (size_t i = 0; i < p.size(); ++i) {
    require(p[i].allFinite(), "add_clumps: positions must be finite");
    require(std::isfinite(f[i]) && f[i] > 0, "add_clumps: scales must be finite numbers > 0");
    const Quat o(q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]);
    require(o.coeffs().allFinite() && o.norm() > 0, "add_clumps: orientations must be finite, non-zero quaternions");
  }
  for (size_t i = 0; i < p.size(); ++i)
    s.addClump(p[i], Quat(q[4 * i], q[4 * i + 1], q[4 * i + 2], q[4 * i + 3]), t, f[i]);
}

Real clumpVolume(const bp::object& centres, const bp::object& radii) {
  return cachedClumpVolume(toVec3List(centres, "member centres"), toRealList(radii, "member radii"));
}

}  // namespace

void exportClump() {
  bp::class_<ClumpTemplate, TemplatePtr>("ClumpTemplate",
                                         "Rigid union of overlapping balls; mass properties of the union from CGAL.",
                                         bp::no_init)
      .def("__init__", bp::make_constructor(&makeTemplate, bp::default_call_policies(),
                                            (bp::arg("centres"), bp::arg("radii"), bp::arg("levels") = 4)))
      .add_property("offsets", &offsets, "Member centres in the template (principal) frame.")
      .add_property("radii", &radii)
      .def_readonly("volume", &ClumpTemplate::volume, "Solid volume of the union (overlaps once).")
      .add_property("inertia", &inertia, "Principal moments per unit density, ascending (m^5).")
      .add_property("centroid", &centroid, "Centroid in the frame the members were given in.")
      .add_property("axes", &axes, "Principal axes (columns) in the frame the members were given in.")
      .def_readonly("volume_error_estimate", &ClumpTemplate::volumeErrorEstimate)
      .add_property("bounding_radius", &ClumpTemplate::boundingRadius)
      .add_property("equivalent_diameter", &ClumpTemplate::equivalentDiameter)
      .add_property("size", &ClumpTemplate::size)
      .def("scaled", &scaled);
  bp::def("clump_volume", &clumpVolume, (bp::arg("centres"), bp::arg("radii")),
          "Union volume of member balls (cached per shape).");
  bp::def("add_clumps", &addClumps,
          (bp::arg("scene"), bp::arg("template"), bp::arg("positions"), bp::arg("orientations"), bp::arg("scales")));
}

}  // namespace trueaniso::py
