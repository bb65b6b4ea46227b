// The `vio` command line: a thin main over the tools library.
#include "vio/cli/cli.h"

int main(int argc, char** argv) { return vio::tools::RunCli(argc, argv); }
