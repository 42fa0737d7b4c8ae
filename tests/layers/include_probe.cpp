// Compiled with the usage requirements of one layer of the library (tests/layers/CMakeLists.txt):
// it includes QSIL_PROBE_HEADER, a header of that layer, of a lower one, or of a higher one.
#include QSIL_PROBE_HEADER

int qsil_layer_probe() { return 0; }
