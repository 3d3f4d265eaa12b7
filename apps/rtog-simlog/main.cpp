// rtog-simlog: a 2D laser rawlog simulated in an MRPT gridmap. All logic lives in simlog.cpp.
#include <iostream>

#include "simlog.hpp"

int main(int argc, char** argv) { return rtog::simlog::main(argc, argv, std::cout, std::cerr); }
