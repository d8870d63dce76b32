#pragma once
// The Voigt notation lives in core/Voigt.hpp (the cell controllers use it too); kept here so the
// statics' includes read as before.
#include "core/Voigt.hpp"
