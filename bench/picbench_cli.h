#pragma once
/// `picbench`: benchmarks that print numbers and write JSON (never assert).

namespace pic {

/// Runs picbench with command-line arguments; returns the process exit code.
int picbenchMain(int argc, char** argv);

}  // namespace pic
