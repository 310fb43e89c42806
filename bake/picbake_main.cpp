#include "bake/picbake_cli.h"

int main(int argc, char** argv) { return pic::picbakeMain(argc, argv); }
