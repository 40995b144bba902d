#include <mgn/core/build_info.hpp>
#include <mgn/version.hpp>

#include <GL/osmesa.h>
#include <LinearMath/btScalar.h>
#include <assimp/version.h>
#include <embree3/rtcore_config.h>
#include <fcl/config.h>

#include <Eigen/Core>
#include <nlopt.hpp>
#include <opencv2/core/utility.hpp>
#include <string>

namespace mgn {

std::string version() { return MGN_VERSION_STRING; }

std::vector<std::pair<std::string, std::string>> build_info() {
  auto str = [](auto... parts) {
    std::string s;
    ((s += std::to_string(parts), s += '.'), ...);
    s.pop_back();
    return s;
  };
  int nl_major = 0, nl_minor = 0, nl_bugfix = 0;
  nlopt::version(nl_major, nl_minor, nl_bugfix);
  const int bullet = btGetVersion();
  return {
      {"mgn", MGN_VERSION_STRING},
      {"eigen", str(EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION)},
      {"embree", RTC_VERSION_STRING},
      {"fcl", FCL_VERSION},
      {"assimp", str(aiGetVersionMajor(), aiGetVersionMinor(), aiGetVersionPatch())},
      {"bullet", str(bullet / 100, bullet % 100)},
      {"nlopt", str(nl_major, nl_minor, nl_bugfix)},
      {"opencv", cv::getVersionString()},
      {"osmesa-api", str(OSMESA_MAJOR_VERSION, OSMESA_MINOR_VERSION)},
  };
}

}  // namespace mgn
