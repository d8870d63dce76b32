#include "dynamics/ContactRefresh.hpp"

#include "dynamics/ContactDetection.hpp"
#include "dynamics/ContactForces.hpp"

namespace trueaniso {

void refreshContacts(Scene& s) {
  s.validate();
  s.refreshMembers();
  ContactDetection detection;
  detection.rebuild(s);  // keeps the history of every pair it lists again
  s.detectionInvalid = false;
  const Real dt = s.dt;
  s.dt = 0;  // the shear increment v dt vanishes: history is only carried
  try {
    ContactForces().apply(s);
  } catch (...) {
    s.dt = dt;
    throw;
  }
  s.dt = dt;
}

}  // namespace trueaniso
