#include "client/connection.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <mutex>
#include <optional>
#include <random>
#include <thread>
#include <unistd.h>

#include <grpcpp/create_channel.h>
#include <grpcpp/support/client_interceptor.h>

#include "core/gltf_loader.h"
#include "core/sh.h"
#include "proto/wire.h"

namespace pic {

namespace {

namespace fs = std::filesystem;

/// A deadline for unary calls: a server that hangs must not hang the client.
void setDeadline(grpc::ClientContext& context) {
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
}

/// The delay a RESOURCE_EXHAUSTED reply asks for (wire::kRetryAfterMetadata), if any.
std::optional<std::chrono::milliseconds> retryAfter(const grpc::ClientContext& context) {
    const auto& trailers = context.GetServerTrailingMetadata();
    const auto it = trailers.find(wire::kRetryAfterMetadata);
    if (it == trailers.end()) return std::nullopt;
    int64_t ms = 0;
    const auto [end, ec] = std::from_chars(it->second.data(), it->second.data() + it->second.size(), ms);
    if (ec != std::errc{} || ms < 0) return std::nullopt;
    return std::chrono::milliseconds(std::min<int64_t>(ms, 60000));
}

/// Runs `call(context)` about `session` (a fresh context each try) again while `patience`
/// has not passed and it fails UNAVAILABLE (the server drains, the session moved, a replica
/// went away; backoff from 50 ms to 1 s) or RESOURCE_EXHAUSTED with a delay to wait (a rate
/// limit). The session id goes in the metadata load balancers route by.
template <class Call>
grpc::Status retrying(std::chrono::milliseconds patience, const std::string& session, Call call) {
    const auto start = std::chrono::steady_clock::now();
    auto backoff = std::chrono::milliseconds(50);
    for (;;) {
        grpc::ClientContext context;
        setDeadline(context);
        if (!session.empty()) context.AddMetadata(wire::kSessionMetadata, session);
        grpc::Status status = call(context);
        std::chrono::milliseconds wait = backoff;
        if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) {
            const auto asked = retryAfter(context);
            if (!asked) return status;
            wait = *asked;
        } else if (status.error_code() != grpc::StatusCode::UNAVAILABLE) {
            return status;
        } else {
            backoff = std::min(backoff * 2, std::chrono::milliseconds(1000));
        }
        if (std::chrono::steady_clock::now() - start + wait > patience) return status;
        std::this_thread::sleep_for(wait);
    }
}

/// A new session id: 64 random bits as 16 lowercase hex digits.
std::string drawSessionId() {
    static std::mutex mutex;
    static std::random_device random;
    std::lock_guard lock(mutex);
    return fmt::format("{:08x}{:08x}", uint32_t(random()), uint32_t(random()));
}

/// Adds `authorization: Bearer KEY` to every call of a channel.
class ApiKeyInterceptor final : public grpc::experimental::Interceptor {
public:
    explicit ApiKeyInterceptor(const std::string& value) : mValue(value) {}
    void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
        if (methods->QueryInterceptionHookPoint(
                grpc::experimental::InterceptionHookPoints::PRE_SEND_INITIAL_METADATA))
            methods->GetSendInitialMetadata()->emplace(wire::kAuthorizationMetadata, mValue);
        methods->Proceed();
    }

private:
    const std::string& mValue;
};

class ApiKeyInterceptorFactory final : public grpc::experimental::ClientInterceptorFactoryInterface {
public:
    explicit ApiKeyInterceptorFactory(const std::string& key) : mValue("Bearer " + key) {}
    grpc::experimental::Interceptor* CreateClientInterceptor(grpc::experimental::ClientRpcInfo*) override {
        return new ApiKeyInterceptor(mValue);
    }

private:
    std::string mValue;
};

/// An asset name from the server as a path inside `folder`, or InvalidInput when it would
/// leave it (a server must not make a client write anywhere else).
Result<fs::path> assetPath(const fs::path& folder, const std::string& name) {
    fs::path relative(name);
    bool escapes = name.empty() || relative.is_absolute();
    for (const auto& part : relative) escapes = escapes || part == ".." || part == ".";
    if (escapes)
        return fail(ErrorCode::Corrupt, "the server sent an asset named \"{}\", outside its folder",
                    name);
    return folder / relative;
}

Result<void> writeFile(const fs::path& path, const std::string& bytes) {
    std::error_code ec;
    fs::create_directories(path.parent_path(), ec);
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    out.close();
    if (!out) return fail(ErrorCode::Io, "cannot write {}", path.string());
    return {};
}

}  // namespace

FrameStream::FrameStream(v1::Pic::Stub& stub, v1::SubscribeRequest request,
                         std::chrono::milliseconds patience)
    : mStub(stub), mRequest(std::move(request)), mPatience(patience) {
    std::lock_guard lock(mMutex);
    start();
}

FrameStream::~FrameStream() {
    if (!mFinished) finishCall();
}

void FrameStream::start() {
    mContext = std::make_unique<grpc::ClientContext>();
    mContext->AddMetadata(wire::kSessionMetadata, mRequest.session());
    if (mCancelled) mContext->TryCancel();
    mReader = mStub.Subscribe(mContext.get(), mRequest);
}

grpc::Status FrameStream::finishCall() {
    {
        std::lock_guard lock(mMutex);
        mContext->TryCancel();
    }
    v1::Frame drained;
    while (mReader->Read(&drained)) {
    }
    return mReader->Finish();
}

bool FrameStream::next(v1::Frame& frame) {
    if (mFinished) return false;
    // Patience counts from this call, which a frame ends: the time without frames.
    const auto lastFrame = std::chrono::steady_clock::now();
    auto backoff = std::chrono::milliseconds(50);
    for (;;) {
        if (mReader->Read(&frame)) return true;
        grpc::Status status = mReader->Finish();
        const grpc::StatusCode code = status.error_code();
        const bool retryable = code == grpc::StatusCode::UNAVAILABLE ||
                               code == grpc::StatusCode::INTERNAL ||
                               code == grpc::StatusCode::UNKNOWN;
        std::unique_lock lock(mMutex);
        if (!retryable || mCancelled || mPatience.count() == 0 ||
            std::chrono::steady_clock::now() - lastFrame + backoff > mPatience) {
            mStatus = mCancelled ? grpc::Status(grpc::StatusCode::CANCELLED, "cancelled") : status;
            mFinished = true;
            return false;
        }
        mWake.wait_for(lock, backoff, [&] { return mCancelled; });
        backoff = std::min(backoff * 2, std::chrono::milliseconds(2000));
        ++mResubscriptions;
        start();
    }
}

void FrameStream::cancel() {
    {
        std::lock_guard lock(mMutex);
        mCancelled = true;
        mContext->TryCancel();
    }
    mWake.notify_all();
}

grpc::Status FrameStream::status() {
    return mStatus;
}

Result<std::unique_ptr<PicConnection>> PicConnection::connect(const std::string& address,
                                                              const ConnectOptions& options) {
    const std::string& apiKey = options.apiKey;
    const std::string& rootCertsPem = options.rootCertsPem;
    const std::chrono::milliseconds timeout = options.timeout;
    // gRPC refuses metadata values outside printable ASCII; say so instead of failing each call.
    if (!std::ranges::all_of(apiKey, [](char c) { return c > ' ' && c < 127; }))
        return fail(ErrorCode::InvalidInput,
                    "the API key holds a space or a character outside printable ASCII");
    if (options.keepalive < std::chrono::seconds(1))
        return fail(ErrorCode::InvalidInput, "keepalive must be at least 1 s, got {} ms",
                    options.keepalive.count());
    grpc::ChannelArguments arguments;
    arguments.SetMaxReceiveMessageSize(int(wire::kMaxReplyBytes));
    arguments.SetMaxSendMessageSize(int(wire::kMaxRequestBytes));
    const int keepaliveMs = int(std::min<int64_t>(options.keepalive.count(), INT32_MAX));
    arguments.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, keepaliveMs);
    arguments.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, std::min(keepaliveMs, 10000));
    arguments.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
    // A stream can be quiet for minutes (no light changes): keep pinging through the silence.
    arguments.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
    auto connection = std::unique_ptr<PicConnection>(new PicConnection());
    connection->mAddress = address;
    std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials();
    if (!rootCertsPem.empty()) {
        grpc::SslCredentialsOptions ssl;
        ssl.pem_root_certs = rootCertsPem;
        credentials = grpc::SslCredentials(ssl);
    }
    if (apiKey.empty()) {
        connection->mChannel = grpc::CreateCustomChannel(address, credentials, arguments);
    } else {
        std::vector<std::unique_ptr<grpc::experimental::ClientInterceptorFactoryInterface>> interceptors;
        interceptors.push_back(std::make_unique<ApiKeyInterceptorFactory>(apiKey));
        connection->mChannel = grpc::experimental::CreateCustomChannelWithInterceptors(
            address, credentials, arguments, std::move(interceptors));
    }
    if (!connection->mChannel->WaitForConnected(std::chrono::system_clock::now() + timeout))
        return fail(ErrorCode::Io, "cannot reach a picserver at {} (waited {} ms{})", address,
                    timeout.count(),
                    rootCertsPem.empty() ? "; a TLS server needs --tls-ca"
                                         : "; with TLS: is the server's certificate signed by "
                                           "--tls-ca and valid for this address?");
    connection->mStub = v1::Pic::NewStub(connection->mChannel);
    return connection;
}

Result<v1::ListBakesResponse> PicConnection::listBakes() {
    grpc::ClientContext context;
    setDeadline(context);
    v1::ListBakesResponse response;
    grpc::Status status = mStub->ListBakes(&context, v1::ListBakesRequest(), &response);
    if (!status.ok()) return std::unexpected(wire::fromStatus(status, "ListBakes"));
    return response;
}

Result<v1::CreateSessionResponse> PicConnection::createSession(const std::string& bakeId) {
    v1::CreateSessionRequest request;
    request.set_bake_id(bakeId);
    v1::CreateSessionResponse response;
    // A new id each try: a try that failed on its way back may have created its session
    // (which then idles out unused).
    grpc::Status status = retrying(mPatience, "", [&](grpc::ClientContext& context) {
        request.set_session(drawSessionId());
        context.AddMetadata(wire::kSessionMetadata, request.session());
        return mStub->CreateSession(&context, request, &response);
    });
    if (!status.ok()) return std::unexpected(wire::fromStatus(status, "CreateSession"));
    return response;
}

Result<v1::JoinSessionResponse> PicConnection::joinSession(const std::string& session,
                                                           const std::string& token) {
    v1::JoinSessionRequest request;
    request.set_session(session);
    request.set_token(token);
    v1::JoinSessionResponse response;
    grpc::Status status = retrying(mPatience, session, [&](grpc::ClientContext& context) {
        return mStub->JoinSession(&context, request, &response);
    });
    if (!status.ok()) return std::unexpected(wire::fromStatus(status, "JoinSession"));
    return response;
}

Result<v1::SessionStats> PicConnection::stats(const std::string& session,
                                             const std::string& token) {
    v1::GetStatsRequest request;
    request.set_session(session);
    request.set_token(token);
    v1::SessionStats response;
    grpc::Status status = retrying(mPatience, session, [&](grpc::ClientContext& context) {
        return mStub->GetStats(&context, request, &response);
    });
    if (!status.ok()) return std::unexpected(wire::fromStatus(status, "GetStats"));
    return response;
}

Result<uint64_t> PicConnection::setLights(const std::string& session, const std::string& token,
                                          const LightSet& lights) {
    v1::SetLightsRequest request;
    request.set_session(session);
    request.set_token(token);
    *request.mutable_lights() = wire::toProto(lights);
    v1::SetLightsResponse response;
    grpc::Status status = retrying(mPatience, session, [&](grpc::ClientContext& context) {
        return mStub->SetLights(&context, request, &response);
    });
    if (!status.ok()) return std::unexpected(wire::fromStatus(status, "SetLights"));
    return response.version();
}

Result<v1::SceneHeader> PicConnection::getScene(const std::string& bakeId, bool headerOnly,
                                                const std::string& folder) {
    grpc::ClientContext context;
    v1::GetSceneRequest request;
    request.set_bake_id(bakeId);
    request.set_header_only(headerOnly);
    auto reader = mStub->GetScene(&context, request);
    v1::SceneChunk chunk;
    if (!reader->Read(&chunk) || !chunk.has_header()) {
        grpc::Status status = reader->Finish();
        if (!status.ok()) return std::unexpected(wire::fromStatus(status, "GetScene"));
        return fail(ErrorCode::Corrupt, "GetScene: the stream did not start with a header");
    }
    const v1::SceneHeader header = chunk.header();
    std::string pending;  // bytes received and not yet written to an asset
    int asset = 0;
    const auto flush = [&]() -> Result<void> {
        while (asset < header.assets_size() && pending.size() >= header.assets(asset).size()) {
            const v1::AssetInfo& info = header.assets(asset);
            PIC_TRY_ASSIGN(fs::path path, assetPath(folder, info.name()));
            PIC_TRY(writeFile(path, pending.substr(0, info.size())));
            pending.erase(0, info.size());
            ++asset;
        }
        return {};
    };
    uint64_t received = 0;
    while (reader->Read(&chunk)) {
        if (headerOnly || !chunk.has_data())
            return fail(ErrorCode::Corrupt, "GetScene: unexpected chunk after the header");
        received += chunk.data().size();
        if (received > header.total_bytes())
            return fail(ErrorCode::Corrupt, "GetScene: more bytes than the header's {}",
                        header.total_bytes());
        pending += chunk.data();
        PIC_TRY(flush());
    }
    grpc::Status status = reader->Finish();
    if (!status.ok()) return std::unexpected(wire::fromStatus(status, "GetScene"));
    if (!headerOnly) {
        PIC_TRY(flush());
        if (received != header.total_bytes() || asset != header.assets_size())
            return fail(ErrorCode::Corrupt, "GetScene: received {} of {} bytes", received,
                        header.total_bytes());
    }
    return header;
}

namespace {

constexpr const char* kHeaderFile = "header.pb";

Result<std::string> readAsset(const fs::path& folder, const std::string& name) {
    PIC_TRY_ASSIGN(fs::path path, assetPath(folder, name));
    std::ifstream file(path, std::ios::binary);
    if (!file) return fail(ErrorCode::Corrupt, "{} is missing", path.string());
    return std::string{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

/// An index map asset: `entries` little-endian u32, each a cache below `caches` or kNoCache.
Result<std::vector<uint32_t>> readIndexMap(const fs::path& folder, const std::string& name,
                                           uint64_t entries, uint32_t caches) {
    PIC_TRY_ASSIGN(std::string bytes, readAsset(folder, name));
    if (bytes.size() != entries * sizeof(uint32_t))
        return fail(ErrorCode::Corrupt, "{} holds {} bytes for {} entries of 4", name, bytes.size(),
                    entries);
    std::vector<uint32_t> map(entries);
    if (!map.empty()) std::memcpy(map.data(), bytes.data(), bytes.size());
    for (size_t i = 0; i < map.size(); ++i)
        if (map[i] != kNoCache && map[i] >= caches)
            return fail(ErrorCode::Corrupt, "{} entry {} names cache {} of {}", name, i, map[i],
                        caches);
    return map;
}

/// Loads the scene and layout kept in `folder` for `header`.
Result<ClientScene> loadClientScene(const fs::path& folder, const v1::SceneHeader& header) {
    ClientScene client;
    client.header = header;
    client.folder = folder.string();
    PIC_TRY_ASSIGN(fs::path scenePath, assetPath(folder, header.scene_file()));
    PIC_TRY_ASSIGN(client.scene, loadScene(scenePath.string()));
    if (client.scene.hash != header.scene_hash())
        return fail(ErrorCode::Corrupt,
                    "the downloaded scene has hash {:016x}, the server's bake is of {:016x}",
                    client.scene.hash, header.scene_hash());

    PIC_TRY_ASSIGN(std::string uvs, readAsset(folder, "layout/triangle_uvs"));
    if (uvs.size() != client.scene.triangles.size() * 3 * sizeof(glm::vec2))
        return fail(ErrorCode::Corrupt, "layout/triangle_uvs holds {} bytes for {} triangles",
                    uvs.size(), client.scene.triangles.size());
    client.triangleUvs.resize(client.scene.triangles.size() * 3);
    if (!uvs.empty()) std::memcpy(client.triangleUvs.data(), uvs.data(), uvs.size());
    const uint32_t bandsY = header.bands_y(), bandsC = header.bands_c();
    if (bandsY < 1 || bandsY > uint32_t(kMaxShBands) || bandsC > bandsY)
        return fail(ErrorCode::Corrupt,
                    "the header's band counts {} (luma) and {} (chroma) are out of range", bandsY,
                    bandsC);
    const uint64_t vertices =
        uint64_t(header.grid().dims_x()) * header.grid().dims_y() * header.grid().dims_z();
    const uint64_t texels = uint64_t(header.lightmap_width()) * header.lightmap_height();
    // Every cache is held by a grid vertex or a light-map texel.
    if (header.caches() > vertices + texels)
        return fail(ErrorCode::Corrupt,
                    "the header names {} caches for {} grid vertices and {} texels",
                    header.caches(), vertices, texels);
    PIC_TRY_ASSIGN(client.gridCaches,
                   readIndexMap(folder, "layout/grid_caches", vertices, header.caches()));
    PIC_TRY_ASSIGN(client.lightmapCaches,
                   readIndexMap(folder, "layout/lightmap_caches", texels, header.caches()));
    return client;
}

}  // namespace

Result<ClientScene> PicConnection::fetchScene(const std::string& bakeId,
                                              const std::string& cacheDir, bool* downloaded) {
    if (downloaded) *downloaded = false;
    PIC_TRY_ASSIGN(v1::SceneHeader header, getScene(bakeId, true, ""));
    if (header.bake_id().empty() || header.bake_id().find_first_of("/.") != std::string::npos)
        return fail(ErrorCode::Corrupt, "GetScene: bake id \"{}\" is not a folder name",
                    header.bake_id());
    const fs::path root(cacheDir);
    const fs::path folder = root / header.bake_id();

    // A kept copy counts only if it was written for exactly this header (written last).
    std::string serialized;
    header.SerializeToString(&serialized);
    if (auto kept = readAsset(folder, kHeaderFile); kept && *kept == serialized) {
        auto loaded = loadClientScene(folder, header);
        if (loaded) return loaded;
        std::fprintf(stderr, "picclient: the scene kept in %s is unusable (%s); downloading it again\n",
                     folder.string().c_str(), loaded.error().message.c_str());
    }

    // Into a fresh folder first, renamed into place when complete: a crash or a second client
    // never leaves a half-written scene where the next run would load it.
    const fs::path staging = root / fmt::format("{}.tmp-{}", header.bake_id(), getpid());
    std::error_code ec;
    fs::remove_all(staging, ec);
    fs::create_directories(staging, ec);
    if (ec) return fail(ErrorCode::Io, "cannot create {}: {}", staging.string(), ec.message());
    auto full = getScene(header.bake_id(), false, staging.string());
    if (!full) {
        fs::remove_all(staging, ec);
        return std::unexpected(full.error());
    }
    full->SerializeToString(&serialized);
    PIC_TRY(writeFile(staging / kHeaderFile, serialized));
    fs::remove_all(folder, ec);
    fs::rename(staging, folder, ec);
    if (ec)
        return fail(ErrorCode::Io, "cannot move {} to {}: {}", staging.string(), folder.string(),
                    ec.message());
    if (downloaded) *downloaded = true;
    return loadClientScene(folder, *full);
}

std::unique_ptr<FrameStream> PicConnection::subscribe(const std::string& session,
                                                      const std::string& token,
                                                      std::chrono::milliseconds patience) {
    v1::SubscribeRequest request;
    request.set_session(session);
    request.set_token(token);
    return std::make_unique<FrameStream>(*mStub, std::move(request), patience);
}

Result<v1::SceneHeader> PicConnection::sceneHeader(const std::string& bakeId) {
    return getScene(bakeId, true, "");
}

FrameDecoder::FrameDecoder(const v1::SceneHeader& header) {
    const size_t caches = header.caches();
    const size_t y = size_t{header.bands_y()} * header.bands_y();
    const size_t c = size_t{header.bands_c()} * header.bands_c();
    mExpected = {caches * y, caches * c, caches * c};
}

Result<void> FrameDecoder::apply(v1::Frame& frame) {
    if (frame.base_version() != 0 &&
        (frame.base_version() != mVersion || frame.base_part() != mPart))
        return fail(ErrorCode::Corrupt,
                    "frame of version {} part {} is a delta against version {} part {}, but "
                    "version {} part {} is held",
                    frame.version(), frame.part(), frame.base_version(), frame.base_part(),
                    mVersion, mPart);
    std::optional<LightSet> lights;
    if (frame.has_lights()) {
        auto parsed = wire::fromProto(frame.lights());
        if (!parsed)
            return fail(ErrorCode::Corrupt, "frame of version {}: its light set: {}",
                        frame.version(), parsed.error().message);
        lights = std::move(*parsed);
    }
    PIC_TRY_ASSIGN(EncodedFrame encoded, wire::planesFromProto(frame));
    for (int t = 0; t < kFramePlanes; ++t)
        if (encoded.planes[size_t(t)].values != mExpected[size_t(t)])
            return fail(ErrorCode::Corrupt,
                        "frame of version {}: plane {} holds {} values, the scene's caches {}",
                        frame.version(), framePlaneName(t), encoded.planes[size_t(t)].values,
                        mExpected[size_t(t)]);
    if (encoded.key()) {
        // Decode a key frame into a copy so that a corrupt one changes nothing.
        HalfFrame decoded;
        for (int t = 0; t < kFramePlanes; ++t)
            decoded.planes[size_t(t)].resize(encoded.planes[size_t(t)].values);
        PIC_TRY(decodeFrame(encoded, decoded));
        mFrame = std::move(decoded);
    } else {
        PIC_TRY(decodeFrame(encoded, mFrame));
    }
    mVersion = frame.version();
    mPart = frame.part();
    if (lights) mLights = std::move(*lights);
    return {};
}

CacheIndexMaps ClientScene::indexMaps() const {
    return CacheIndexMaps{
        glm::uvec3(header.grid().dims_x(), header.grid().dims_y(), header.grid().dims_z()),
        gridCaches, header.lightmap_width(), header.lightmap_height(), lightmapCaches};
}

Result<CacheValues> cacheValuesOf(const ClientScene& scene, const HalfFrame& frame) {
    const v1::SceneHeader& header = scene.header;
    return cacheValuesOf(frame, header.caches(), header.bands_y(), header.bands_c());
}

CacheTextures cacheTexturesOf(const ClientScene& scene, const CacheValues& values) {
    const CacheIndexMaps maps = scene.indexMaps();
    CacheTextures textures =
        makeCacheTextures(maps, scene.header.bands_y(), scene.header.bands_c());
    copyCachesToTextures(maps, values, textures);
    return textures;
}

Result<CacheTextures> cacheTexturesOf(const ClientScene& scene, const HalfFrame& frame) {
    PIC_TRY_ASSIGN(CacheValues values, cacheValuesOf(scene, frame));
    return cacheTexturesOf(scene, values);
}

ClientLayout clientLayoutOf(const ClientScene& scene) {
    const v1::SceneHeader& header = scene.header;
    ClientLayout layout;
    layout.sceneHash = header.scene_hash();
    layout.bandsY = header.bands_y();
    layout.bandsC = header.bands_c();
    layout.gridOrigin = glm::vec3(header.grid().origin().x(), header.grid().origin().y(),
                                  header.grid().origin().z());
    layout.gridCellSize = header.grid().cell_size();
    layout.gridDims = glm::uvec3(header.grid().dims_x(), header.grid().dims_y(), header.grid().dims_z());
    layout.lightmapWidth = header.lightmap_width();
    layout.lightmapHeight = header.lightmap_height();
    layout.triangleUvs = scene.triangleUvs;
    return layout;
}

}  // namespace pic
