// The sessions a server restores: the JSON session database of earlier releases (converted
// at start), whose rows then go through the same check as SQLite's and PostgreSQL's.

#include "fuzz/fuzz.h"
#include "server/session_store.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace pic;
    const auto sessions = parseJsonSessions(std::string(fuzz::text(data, size)), "sessions.json");
    if (!sessions) return 0;
    for (const StoredSession& session : *sessions) {
        PIC_CHECK(session.version >= 1);
        PIC_CHECK(session.editorDigest.size() == 64 && session.viewerDigest.size() == 64);
    }
    return 0;
}
