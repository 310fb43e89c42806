#include "tests/client/stream_fixture.h"

#include <cctype>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <future>

#include <arpa/inet.h>
#include <grpcpp/generic/generic_stub.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include "tests/support/baked_scene.h"

namespace pic::test {

const std::string kScene = testScenePath("cornell");

const std::string& bakePath() {
    BakeOptions options = smallBakeOptions(2048, 32);
    options.bandsY = 3;
    options.bandsC = 2;
    return bakeFile("cornell", options);
}

Served serve(const std::string& backend, uint32_t keyframeInterval,
             std::chrono::milliseconds sessionIdle, const std::string& dbPath) {
    ServerOptions options;
    options.session.keyframeInterval = keyframeInterval;
    // The stream tests push light sets back to back; the rate limit has a test of its own.
    options.session.setLightsPerSecond = 1e6;
    options.sessionIdle = sessionIdle;
    options.dbPath = dbPath;
    return serveWith(options, backend);
}

Result<std::unique_ptr<PicServer>> startOn(const ServerOptions& options,
                                           const std::string& backend, int bounces) {
    ServeOptions serveOptions;
    serveOptions.backend = backend;
    serveOptions.bounces.bounces = bounces;
    auto bake = ServedBake::load(bakePath(), kScene, serveOptions);
    if (!bake) return std::unexpected(bake.error());
    std::vector<std::unique_ptr<ServedBake>> bakes;
    bakes.push_back(std::move(*bake));
    return PicServer::start(std::move(bakes), "127.0.0.1:0", options);
}

Served serveWith(const ServerOptions& serverOptions, const std::string& backend, int bounces) {
    Served served;
    auto server = startOn(serverOptions, backend, bounces);
    EXPECT_TRUE(server) << (server ? "" : server.error().message);
    if (!server) return served;
    served.server = std::move(*server);
    auto connection = PicConnection::connect(served.server->address());
    EXPECT_TRUE(connection) << (connection ? "" : connection.error().message);
    if (connection) served.connection = std::move(*connection);
    return served;
}

Result<std::unique_ptr<PicServer>> startWithDatabase(const std::string& dbPath) {
    ServerOptions options;
    options.dbPath = dbPath;
    return startOn(options, "cpu", -1);
}

LightSet pointLight(float x) {
    LightSet lights;
    Light light;
    light.id = "lamp";
    light.type = LightType::Point;
    light.position = glm::vec3(x, 0.5f, 0.0f);  // inside the box (ceiling at y = 1)
    light.intensity = 4.0f;
    lights.lights.push_back(light);
    return lights;
}

v1::SceneHeader sceneHeaderOf(PicConnection& connection) {
    auto header = connection.sceneHeader("");
    EXPECT_TRUE(header) << (header ? "" : header.error().message);
    return header ? *header : v1::SceneHeader{};
}


Child::Child(const std::vector<std::string>& args) {
    int fds[2];
    if (pipe(fds) != 0) return;
    const pid_t pid = fork();
    if (pid == 0) {
        dup2(fds[1], STDOUT_FILENO);
        close(fds[0]);
        close(fds[1]);
        std::vector<char*> argv;
        for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
        argv.push_back(nullptr);
        execv(argv[0], argv.data());
        _exit(127);
    }
    close(fds[1]);
    mPid = pid;
    mOut = fdopen(fds[0], "r");
}

Child::~Child() {
    if (mPid > 0) {
        ::kill(mPid, SIGKILL);
        wait();
    }
    if (mOut) std::fclose(mOut);
}

Child::Child(Child&& other) noexcept
    : mPid(std::exchange(other.mPid, -1)), mOut(std::exchange(other.mOut, nullptr)) {}

Child& Child::operator=(Child&& other) noexcept {
    std::swap(mPid, other.mPid);
    std::swap(mOut, other.mOut);
    return *this;
}

void Child::signal(int signal) const {
    if (mPid > 0) ::kill(mPid, signal);
}

int Child::wait() {
    if (mPid <= 0) return -1;
    int status = 0;
    waitpid(std::exchange(mPid, -1), &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::optional<int> Child::waitFor(std::chrono::milliseconds timeout) {
    if (mPid <= 0) return -1;
    const auto end = std::chrono::steady_clock::now() + timeout;
    int status = 0;
    while (waitpid(mPid, &status, WNOHANG) == 0) {
        if (std::chrono::steady_clock::now() > end) return std::nullopt;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    mPid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string readLine(FILE* file) {
    char line[4096];
    if (!std::fgets(line, sizeof line, file)) return {};
    std::string text(line);
    if (!text.empty() && text.back() == '\n') text.pop_back();
    return text;
}

std::string run(const std::string& command, int& exit) {
    std::string output;
    FILE* pipe = popen(command.c_str(), "r");
    char buffer[4096];
    while (size_t n = std::fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
    exit = WEXITSTATUS(pclose(pipe));
    return output;
}

int HttpReply::code() const {
    // "HTTP/1.1 200 OK"
    const size_t space = status.find(' ');
    if (!status.starts_with("HTTP/") || space == std::string::npos) return 0;
    return std::atoi(status.c_str() + space + 1);
}

std::string HttpReply::header(const std::string& name) const {
    const auto lower = [](std::string text) {
        for (char& c : text) c = char(std::tolower(static_cast<unsigned char>(c)));
        return text;
    };
    const std::string wanted = lower(name) + ":";
    for (const std::string& line : headers)
        if (lower(line).starts_with(wanted)) {
            const size_t start = line.find_first_not_of(' ', wanted.size());
            return start == std::string::npos ? std::string() : line.substr(start);
        }
    return {};
}

HttpReply httpRequest(const std::string& address, const std::string& method,
                      const std::string& path, const std::string& body,
                      const std::vector<std::string>& headers) {
    const size_t colon = address.rfind(':');
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in to{};
    to.sin_family = AF_INET;
    to.sin_port = htons(uint16_t(std::stoi(address.substr(colon + 1))));
    ::inet_pton(AF_INET, address.substr(0, colon).c_str(), &to.sin_addr);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&to), sizeof to) != 0) {
        ::close(fd);
        return {"error: cannot connect to " + address, "", {}};
    }
    std::string request = method + " " + path + " HTTP/1.1\r\nHost: " + address +
                          "\r\nConnection: close\r\n";
    for (const std::string& header : headers) request += header + "\r\n";
    if (!body.empty() || method == "POST")
        request += "Content-Length: " + std::to_string(body.size()) + "\r\n";
    request += "\r\n" + body;
    // A server may answer before it read all of a large body, and close: what it sent counts.
    for (size_t sent = 0; sent < request.size();) {
        const ssize_t n = ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
        if (n <= 0) break;
        sent += size_t(n);
    }
    std::string reply;
    char buffer[65536];
    for (ssize_t n; (n = ::read(fd, buffer, sizeof buffer)) > 0;) reply.append(buffer, size_t(n));
    ::close(fd);
    const size_t lineEnd = reply.find("\r\n");
    const size_t bodyStart = reply.find("\r\n\r\n");
    if (lineEnd == std::string::npos || bodyStart == std::string::npos)
        return {"error: no HTTP reply", reply, {}};
    HttpReply out{reply.substr(0, lineEnd), reply.substr(bodyStart + 4), {}};
    for (size_t start = lineEnd + 2; start < bodyStart;) {
        const size_t end = reply.find("\r\n", start);
        out.headers.push_back(reply.substr(start, end - start));
        start = end + 2;
    }
    return out;
}

HttpReply httpGet(const std::string& address, const std::string& path) {
    return httpRequest(address, "GET", path);
}

double metricValue(const std::string& text, const std::string& series) {
    const std::string prefix = series + " ";
    for (size_t start = 0; start < text.size();) {
        size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        if (text.compare(start, prefix.size(), prefix) == 0)
            return std::stod(text.substr(start + prefix.size(), end - start - prefix.size()));
        start = end + 1;
    }
    return -1.0;
}

std::string healthStatus(const std::string& address) {
    // grpc.health.v1.Health/Check with an empty request (the whole server); the reply is a
    // HealthCheckResponse: SERVING is the two bytes 08 01, NOT_SERVING 08 02.
    auto channel = grpc::CreateChannel(address, grpc::InsecureChannelCredentials());
    grpc::GenericStub stub(channel);
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    grpc::ByteBuffer request, response;
    grpc::Slice empty("");
    request = grpc::ByteBuffer(&empty, 1);
    std::promise<grpc::Status> done;
    stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request,
                   &response, [&](grpc::Status status) { done.set_value(status); });
    const grpc::Status status = done.get_future().get();
    if (!status.ok()) return "error: " + status.error_message();
    std::vector<grpc::Slice> slices;
    if (!response.Dump(&slices).ok()) return "error: unreadable reply";
    std::string bytes;
    for (const auto& slice : slices)
        bytes.append(reinterpret_cast<const char*>(slice.begin()), slice.size());
    if (bytes == std::string("\x08\x01", 2)) return "SERVING";
    if (bytes == std::string("\x08\x02", 2)) return "NOT_SERVING";
    return "unknown reply of " + std::to_string(bytes.size()) + " bytes";
}

}  // namespace pic::test
