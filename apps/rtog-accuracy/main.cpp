// rtog-accuracy: rtog vs OctoMap vs MRPT's dense grids against the ground truth of a seeded
// synthetic world. All logic lives in accuracy.cpp.
#include <iostream>

#include "accuracy.hpp"

int main(int argc, char** argv) { return rtog::accuracy::main(argc, argv, std::cout, std::cerr); }
