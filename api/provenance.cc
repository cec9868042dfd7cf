#include "api/provenance.h"

#include "enavi_build_info.h"

namespace enavi::api {

std::string BuildVersion() { return ENAVI_BUILD_VERSION; }
std::string BuildCommit() { return ENAVI_BUILD_COMMIT; }

}  // namespace enavi::api
