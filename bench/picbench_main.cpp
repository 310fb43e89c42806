#include "bench/picbench_cli.h"

int main(int argc, char** argv) { return pic::picbenchMain(argc, argv); }
