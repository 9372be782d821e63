// Foundation from sections: accuracy vs time of the quality knobs (samples per side N, angular
// steps M) and the paper-scale run; the tables are those of `candi bench foundation`
// (bench/foundation_accuracy.cc, in the candi_bench library this program links).
#include "bench/bench.h"

int main() { return candi::bench::RunFoundationAccuracy(); }
