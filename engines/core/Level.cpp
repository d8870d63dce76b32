#include "core/Level.hpp"

namespace trueaniso {

// TRUEANISO_KERNEL_LEVEL is set by the build for each compile of the hot sources (engines/CMakeLists.txt).
#ifndef TRUEANISO_KERNEL_LEVEL
#define TRUEANISO_KERNEL_LEVEL "x86-64"
#endif

const char* kernelLevel() { return TRUEANISO_KERNEL_LEVEL; }

}  // namespace trueaniso
