// rtog-first-scan: one observation into a fresh MRPT map, in a process of its own; rtog-bench
// runs it for its first-scan rows. All logic lives in first_scan_child.cpp.
#include <iostream>

#include "first_scan.hpp"

int main(int argc, char** argv) { return rtog::bench::firstScanMain(argc, argv, std::cout, std::cerr); }
