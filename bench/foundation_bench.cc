// Foundation from sections: accuracy vs time of the quality knobs (samples per side N, angular
// steps M) and the paper-scale run; the tables are those of `candi bench foundation`
// (apps/cmd_bench_foundation.cc, compiled into this program too).
#include "apps/commands.h"

int main() { return candi::app::RunBenchFoundation(); }
