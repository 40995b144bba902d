#pragma once
// `mgn-cli pj`: parallel-jaw labels of one mesh (antipodal sampler + wrench score).
#include <string>
#include <vector>

namespace mgn_cli {

/// Usage text of the pj command (for the main help).
extern const char* kPjUsage;

/// Runs `mgn-cli pj ARGS`; returns the exit code. Throws mgn::Error on bad input or failure.
int cmd_pj(const std::vector<std::string>& args);

}  // namespace mgn_cli
