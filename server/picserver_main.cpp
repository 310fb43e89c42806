#include "server/picserver_cli.h"

int main(int argc, char** argv) { return pic::picserverMain(argc, argv); }
