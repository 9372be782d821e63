// Entry points of commands an executable does not contain (main.cc hands those calls over to the
// sibling executable before parsing, so these are never reached; they exist so that cli.cc, the
// same in every executable, links). CANDI_STUB_RELIEF and CANDI_STUB_PCL choose the groups.
#include "apps/commands.h"
#include "apps/relief.h"
#include "core/check.h"

namespace candi::apps {

namespace {
[[noreturn]] void HandedOver(const char* command) {
  throw InternalError(std::string("`") + command + "` is run by a sibling executable; main.cc should have handed it over");
}
}  // namespace

#if CANDI_STUB_RELIEF
int RunReliefSynth(const ReliefSynthArgs&) { HandedOver("relief synth"); }
int RunReliefDataset(const ReliefDatasetArgs&) { HandedOver("relief dataset"); }
int RunReliefTrain(const ReliefTrainArgs&) { HandedOver("relief train"); }
int RunReliefPredict(const ReliefPredictArgs&) { HandedOver("relief predict"); }
int RunReliefPoints(const ReliefPointsArgs&) { HandedOver("relief points"); }
int RunReliefEval(const ReliefEvalArgs&) { HandedOver("relief eval"); }
int RunBenchRelief(const bench::ReliefBenchOptions&) { HandedOver("bench relief"); }
int RunDemo(const DemoArgs&) { HandedOver("demo"); }
#endif
#if CANDI_STUB_PCL
int RunRegister(const RegisterArgs&) { HandedOver("register"); }
int RunRegisterScans(const RegisterScansArgs&) { HandedOver("register-scans"); }
int RunClean(const CleanArgs&) { HandedOver("clean"); }
#endif

}  // namespace candi::apps
