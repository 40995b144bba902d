#pragma once
// `mgn-cli seal`: seal scores of given suction points on a mesh (for cell software that checks
// suction candidates at run time).
#include <string>
#include <vector>

namespace mgn_cli {

/// Usage text of the seal command (for the main help).
extern const char* kSealUsage;

/// Runs `mgn-cli seal ARGS`; returns the exit code. Throws mgn::Error on bad input or failure.
int cmd_seal(const std::vector<std::string>& args);

}  // namespace mgn_cli
