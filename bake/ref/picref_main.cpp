#include <cstring>

#include "bake/ref/picref_cli.h"
#include "bake/ref/picref_shade_cli.h"

// `picref shade …` shades from the runtime's caches; every other form path-traces.
int main(int argc, char** argv) {
    if (argc > 1 && std::strcmp(argv[1], "shade") == 0) return pic::picrefShadeMain(argc - 1, argv + 1);
    return pic::picrefMain(argc, argv);
}
