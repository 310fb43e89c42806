#pragma once
/// The server's database (`picserver --db FILE`): its sessions, so that a restarted server
/// keeps them, with their tokens' digests (server/token_digest.h), bake and last light set.
/// One JSON file, rewritten atomically (temporary file, fsync, rename) by the server's
/// housekeeping thread soon after a session is created, relit or removed (handlers never wait
/// for the disk); readable by its owner only. Format 2 keeps the digests; a format-1 file
/// (plain tokens) still loads, its tokens digested, and the next save writes format 2.

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/light_set.h"

namespace pic {

/// What the database keeps of one session.
struct StoredSession {
    std::string id;
    std::string editorDigest;  ///< tokenDigest of the editor token
    std::string viewerDigest;  ///< tokenDigest of the viewer token
    std::string bakeId;
    uint64_t version = 0;  ///< the newest version it had accepted
    LightSet lights;       ///< the light set of that version
};

class SessionStore {
public:
    explicit SessionStore(std::string path) : mPath(std::move(path)) {}

    const std::string& path() const { return mPath; }
    /// InvalidInput naming the path unless it can hold the database: not a directory, in a
    /// directory that exists and that this process may write in (the file is replaced there).
    static Result<void> checkPath(const std::string& path);
    /// The sessions in the file; none when it does not exist yet. Corrupt naming the file and
    /// the problem when it cannot be read as a database of this format.
    Result<std::vector<StoredSession>> load() const;
    /// Replaces the file's contents with `sessions`; Io naming the file on failure.
    Result<void> save(const std::vector<StoredSession>& sessions);

private:
    std::string mPath;
    std::mutex mMutex;  ///< one writer at a time
};

}  // namespace pic
