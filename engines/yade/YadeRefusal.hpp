#pragma once
// How the plugin's classes refuse (docs/yade-peer.md, "What the classes refuse"):
//  - a bad attribute at construction or assignment: std::invalid_argument from postLoad, which
//    Boost.Python raises as a ValueError naming the attribute ("TrueTriaxialServo.b = 2: ...");
//  - what only the scene can tell (not periodic, a second controller of the cell): the engine's
//    action throws before it changes anything; YADE stops its loop there and O.run(n, True) or
//    O.wait() raise the message as a RuntimeError;
//  - inside YADE's parallel interaction loop (the Ip2 and the law), where an exception would end
//    the process (an exception leaving an OpenMP region calls std::terminate): stopLoopWith
//    hands the message to YADE's loop as an engine's exception would, and the loop stops after
//    this step, so O.run raises it as a RuntimeError too.
#include <core/Omega.hpp>
#include <core/Scene.hpp>
#include <core/ThreadRunner.hpp>

#include <chrono>
#include <iostream>
#include <mutex>
#include <thread>
#include <sstream>
#include <stdexcept>
#include <string>

namespace yade {
namespace trueanisoPlugin {

template <class T> std::string shown(const T& v) {
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

// A Voigt vector as "(a, b, c, d, e, f)".
template <class V> std::string shownVoigt(const V& v) {
  std::string out = "(";
  for (int i = 0; i < 6; ++i) out += (i ? ", " : "") + shown(v[i]);
  return out + ")";
}

// "Class.attribute = value: why"
[[noreturn]] inline void refuse(const std::string& cls, const std::string& attr, const std::string& value,
                                const std::string& why) {
  throw std::invalid_argument(cls + "." + attr + " = " + value + ": " + why);
}

// Omega keeps its simulation loop private (pyOmega, its Python face, is a friend). The member
// pointer is taken through an explicit instantiation, where C++ checks no access: YADE's loop
// offers no other way for an error found inside its interaction loop to reach Python.
template <class Tag, typename Tag::type Member> struct Expose {
  friend typename Tag::type member(Tag) { return Member; }
};
struct OmegaLoop {
  using type = shared_ptr<ThreadRunner> Omega::*;
  friend type member(OmegaLoop);
};
template struct Expose<OmegaLoop, &Omega::simulationLoop>;

// YADE's O.run(n, True) raises an engine's exception only if its wait() finds the run still going
// when it starts polling: a run that ended before (an engine that refuses at the very first step,
// on a loaded machine) returned without a word, the error kept until the next O.run cleared it.
// A moment's pause before the exception leaves the run going while Python reaches wait().
inline void letPythonWait() {
  if (Omega::instance().isRunning()) std::this_thread::sleep_for(std::chrono::milliseconds(200));
}

// An engine's refusal from its action (the scene decides it): raised by O.run as a RuntimeError.
template <class F> void refusingInLoop(F&& f) {
  try {
    f();
  } catch (const std::exception&) {
    letPythonWait();
    throw;
  }
}

// An error found inside YADE's interaction loop (any thread): the loop stops after this step and
// the message is raised in Python by O.run(n, True) / O.wait() (an O.step() only prints it: YADE
// checks for an exception only when a run ends). The first error of a run is kept, and that one
// pauses (letPythonWait), whether or not its message was seen before: the same refusal comes back
// at every run until the scene is corrected (a refused contact is made again each step), and
// utils.createInteraction meets it outside any run, where no pause is needed. The message is
// printed once, not once per contact.
inline void stopLoopWith(Scene* scene, const std::string& what) {
  static std::mutex guard;
  static std::string last;
  std::lock_guard<std::mutex> lock(guard);
  const shared_ptr<ThreadRunner>& loop = Omega::instance().*member(OmegaLoop());
  const bool firstOfRun = loop && !loop->workerThrew;  // YADE's loop clears workerThrew when a run starts
  if (firstOfRun) {
    loop->workerException = std::runtime_error(what);
    loop->workerThrew = true;
  }
  if (scene) scene->stopAtIter = scene->iter + 1;
  if (what != last) {
    std::cerr << "trueaniso: " << what << std::endl;
    last = what;
  }
  if (firstOfRun) letPythonWait();
}

}  // namespace trueanisoPlugin
}  // namespace yade
