// Outputs are written under a temporary name in the same folder and renamed into place, so an
// interrupted bake never leaves a half-written file under a final name, and a file from an
// earlier bake stays intact until its replacement is complete.
#pragma once
#include <functional>
#include <iosfwd>
#include <string>

namespace snow {

// The temporary path used for `finalPath`: same folder and extension (writers choose the format
// by extension), hidden, unique to this process.
std::string temporaryPathFor(const std::string& finalPath);

// Calls write(tempPath); on success renames tempPath to finalPath; on any failure removes the
// temporary file and rethrows.
void writeAtomically(const std::string& finalPath, const std::function<void(const std::string& tempPath)>& write);

// Writes finalPath atomically through a binary output stream: write(stream) fills it; a failed
// open or write throws, naming the file.
void writeStreamAtomically(const std::string& finalPath, const std::function<void(std::ostream& out)>& write);

// Writes `bytes` to finalPath atomically.
void writeTextAtomically(const std::string& finalPath, const std::string& bytes);

}  // namespace snow
