#pragma once
/// `picserver` (ARCHITECTURE.md §5): serves bakes to design-review sessions over gRPC.

namespace pic {

/// Runs picserver with command-line arguments until SIGINT or SIGTERM; returns the exit code.
int picserverMain(int argc, char** argv);

}  // namespace pic
