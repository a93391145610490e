// Linked into every test of a RAYCELL_TSAN build. oneTBB's library is not built with
// ThreadSanitizer, so the synchronization of its task scheduler is invisible to it and every
// hand-over between TBB worker threads looks like a data race (about a thousand reports per
// renderer test). TBB therefore runs on one thread here (all its tasks on the thread that
// starts them), and ThreadSanitizer checks the threads raycell starts itself: the renderer's
// writer thread against the pipeline, the workers of sweep --jobs, concurrent trace reads.
// Races between TBB workers in the tracing stage are not covered (that needs an instrumented
// oneTBB); one and two threads giving byte-identical traces is tested in every build.
#include <tbb/global_control.h>

namespace {
const tbb::global_control serial_tbb(tbb::global_control::max_allowed_parallelism, 1);
}  // namespace
