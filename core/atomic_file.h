// Outputs are written under a temporary name in the same folder and renamed into place, so an
// interrupted bake never leaves a half-written file under a final name, and a file from an
// earlier bake stays intact until its replacement is complete. The temporary name is unique to
// the call (host, process, 64 random bits): two tasks, processes or farm nodes writing the same
// file at once each write their own, and the last rename wins whole.
#pragma once
#include <functional>
#include <iosfwd>
#include <string>

namespace snow {

// Renamed: visible whole or not at all to other processes. Durable: also on disk before the call
// returns (the file fsynced before the rename, the folder after it), so a crash of the machine
// or a reader on another node of shared storage never sees a torn file. Durable costs two fsyncs
// a file: the precompute cache's entries, shared by a farm, use it.
enum class Durability { Renamed, Durable };

// The temporary path used for `finalPath`: same folder and extension (writers choose the format
// by extension), hidden, unique to this call: ".<stem>.tmp-<host>-<pid>-<16 hex digits><ext>".
std::string temporaryPathFor(const std::string& finalPath);

// True for a name temporaryPathFor makes (a file name, no folder).
bool isTemporaryFileName(const std::string& fileName);

// Calls write(tempPath); on success renames tempPath to finalPath; on any failure removes the
// temporary file and rethrows.
void writeAtomically(const std::string& finalPath, const std::function<void(const std::string& tempPath)>& write,
                     Durability durability = Durability::Renamed);

// Writes finalPath atomically through a binary output stream: write(stream) fills it; a failed
// open or write throws, naming the file.
void writeStreamAtomically(const std::string& finalPath, const std::function<void(std::ostream& out)>& write,
                           Durability durability = Durability::Renamed);

// Writes `bytes` to finalPath atomically.
void writeTextAtomically(const std::string& finalPath, const std::string& bytes);

}  // namespace snow
