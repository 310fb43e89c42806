#pragma once
/// `picref SCENE … --out FILE.exr` (the path-traced reference) and `picref probes BAKE.pic …`
/// (path-traced incident radiance at every cache, projected to SH).

namespace pic {

/// Runs picref with command-line arguments; returns the process exit code.
int picrefMain(int argc, char** argv);

}  // namespace pic
