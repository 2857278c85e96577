// IEEE 754 binary16 encoding for the compressed tables' basis: the writer's encoder
// (formats/writer/half_float.hpp), which the f16 feature maps share.
#pragma once

#include "formats/writer/half_float.hpp"

namespace clothbake::compress {

using formats::float_to_half;

}  // namespace clothbake::compress
