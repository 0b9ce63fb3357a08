// The spatial algebra lives in the public header mindyn/spatial.hpp; this path stays for the
// sources that include it under its old name, with the names they use from mindyn::detail.
#pragma once

#include "mindyn/spatial.hpp"

namespace mindyn::detail {
using ::mindyn::sgn;
using ::mindyn::skew;
}  // namespace mindyn::detail
