#include "apps/cli.hpp"

int main(int argc, char** argv) { return lambert::run_cli(argc, argv); }
