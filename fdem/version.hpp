// fdem/version.hpp: what identifies a build: FDEM_VERSION (the release, from CMake) and build_id(), the source tree's
// `git describe --always --dirty` when the library was built (fdem/build_id.cmake; "unknown" outside a git checkout).
// summary.json carries both, and the figures of fdem-tools name them.
#pragma once

namespace fdem {
const char* build_id();
}  // namespace fdem
