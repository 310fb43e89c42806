#pragma once
/// `picref shade SCENE --bake OUT.pic …` (ARCHITECTURE.md §5): runs the runtime passes on one
/// backend and shades a camera view from the caches on the CPU.

namespace pic {

/// argv[0] is "shade"; returns the process exit code.
int picrefShadeMain(int argc, char** argv);

}  // namespace pic
