#pragma once
/// `picclient` (ARCHITECTURE.md §5): session, lights, watch, load and render modes.

namespace pic {

/// Runs picclient with command-line arguments; returns the process exit code.
int picclientMain(int argc, char** argv);

}  // namespace pic
