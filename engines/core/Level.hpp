#pragma once
// The x86-64 level the engines' hot loops were compiled for (engines/CMakeLists.txt): "x86-64" (the
// portable baseline), "x86-64-v3", or the single level of a build for one (TRUEANISO_ARCH). Results
// differ between levels in their last bits (a fused multiply-add rounds once), so a result records
// it (engines.build_arch(), trueaniso/provenance.py).

namespace trueaniso {

const char* kernelLevel();

}  // namespace trueaniso
