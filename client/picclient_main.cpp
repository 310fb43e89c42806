#include "client/picclient_cli.h"

int main(int argc, char** argv) { return pic::picclientMain(argc, argv); }
