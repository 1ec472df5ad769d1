// vdbclay-read-mesh: reads one mesh file with Assimp for vdbclay and answers on stdout (TriangleMesh.h).
// A program of its own, so that a damaged file's crash or endless loop costs only this process, and so
// that vdbclay never forks a copy of itself while its threads hold locks.
#include "voxelize/TriangleMesh.h"

int main(int argc, char** argv) { return vdbclay::meshReaderMain(argc, argv); }
