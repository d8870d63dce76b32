#pragma once
// The Voigt notation lives in core/Voigt.hpp (the cell controllers use it too); this header lets
// the statics include it beside their own headers.
#include "core/Voigt.hpp"
