// Output files are written to a temporary name and renamed when complete (CONTRIBUTING.md
// "Errors"): a reader never sees a half-written file under the final name, and a failed
// write leaves whatever was there before.
#pragma once

#include <functional>
#include <iosfwd>
#include <string>
#include <string_view>

namespace raycell {

// Writes `bytes` to `path` through `path + ".tmp"`: written, flushed, renamed. On any failure
// the temporary is removed, `path` is left as it was, and an InputError names `what` (the
// option or role, e.g. "--out sweep.csv"; `path` when empty) and the cause.
void WriteFileAtomically(const std::string& path, std::string_view bytes,
                         const std::string& what = {});
// The same with the content streamed by `write` (binary mode). If `write` throws, the
// temporary is removed and the exception propagates.
void WriteFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                         const std::string& what = {});
// Reads the whole of `path` (binary) into `bytes`; false, with `bytes` untouched, when it cannot
// be opened (e.g. absent: a sweep's .partial or .checkpoint on a first run).
bool ReadFile(const std::string& path, std::string* bytes);
// Renames a finished temporary `from` to `to`; InputError naming `what` and the system's
// reason on failure. `from` is kept then: a streaming writer's temporary (a capture, a sweep)
// may hold hours of work that the user can still rename by hand.
void RenameFile(const std::string& from, const std::string& to, const std::string& what = {});

}  // namespace raycell
