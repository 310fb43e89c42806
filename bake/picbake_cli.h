#pragma once
/// `picbake bake`, `picbake merge` and `picbake info` (ARCHITECTURE.md §5).

namespace pic {

/// Runs picbake with command-line arguments; returns the process exit code.
int picbakeMain(int argc, char** argv);

}  // namespace pic
