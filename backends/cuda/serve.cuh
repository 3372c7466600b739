// No Rust twin: the other end of crates/testkit/src/command.rs. `fragsim conform` runs its
// `--backend` command once or twice a case; started afresh each time, fragsim_cuda would create a
// CUDA context each time (about a second on an H200, most of a case). The server is one process,
// one context, for many cases: `fragsim_cuda --serve DIR` runs each request exactly as a command
// line with the same arguments would (run_request), and `fragsim_cuda --client DIR ...` is the
// per-case command that hands it a case and waits for its answer.
//
// Protocol (POSIX FIFOs, one client at a time or several: each has its own answer FIFO):
//   DIR/requests  made by the server once its device is up (its existence means "ready"); one
//                 line per case, fields separated by tabs: the client's answer FIFO (absolute),
//                 the client's working directory (the server enters it, so relative paths mean
//                 what they would on a command line), then the command line's arguments
//                 (TRIANGLES OUTDIR [options]); or the line `quit`, which ends the server.
//   answer FIFO   made by the client; the server writes one line into it: `ok`, or
//                 `error: MESSAGE` (a case that could not run; after a device error the server
//                 answers, then stops: the context may be unusable).
// The server holds DIR/requests open for reading and writing, so that it never sees end-of-file
// between clients, and a client's open fails at once (ENXIO) when no server holds it. A client
// that is gone (killed past its timeout) costs the server nothing: its answer is dropped.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <climits>
#include <filesystem>
#include <functional>

#include "device.cuh"

// The exit status of a client that found no server, or whose server ended without answering:
// what `sh` gives a command it cannot run, so that conform stops at once (every further case
// would fail alike) instead of shrinking a case that never ran.
constexpr int STATUS_NO_SERVER = 126;

static std::string requests_fifo(const std::string& dir) { return dir + "/requests"; }

static std::string with_errno(const std::string& what) { return what + ": " + strerror(errno); }

static std::vector<std::string> split_tabs(const std::string& line) {
  std::vector<std::string> fields;
  size_t start = 0;
  for (size_t tab; (tab = line.find('\t', start)) != std::string::npos; start = tab + 1)
    fields.push_back(line.substr(start, tab - start));
  fields.push_back(line.substr(start));
  return fields;
}

// Writes the answer line into the client's FIFO without waiting for a client that is gone. An
// answer of at most PIPE_BUF bytes into an empty pipe is written whole, nonblocking or not.
static void answer_client(const std::string& fifo, std::string answer) {
  for (char& c : answer)
    if (c == '\n') c = ' ';  // one line, whatever the message
  answer = answer.substr(0, PIPE_BUF - 1) + "\n";
  // Only ever a FIFO: a malformed request must not make the server write into (or remove) a file.
  struct stat info;
  if (lstat(fifo.c_str(), &info) != 0 || !S_ISFIFO(info.st_mode)) {
    fprintf(stderr, "fragsim_cuda --serve: %s is no FIFO, no answer\n", fifo.c_str());
    return;
  }
  const int fd = open(fifo.c_str(), O_WRONLY | O_NONBLOCK);
  if (fd < 0) {
    fprintf(stderr, "fragsim_cuda --serve: %s: the client is gone, its answer dropped\n", fifo.c_str());
    unlink(fifo.c_str());
    return;
  }
  if (write(fd, answer.data(), answer.size()) != (ssize_t)answer.size())
    fprintf(stderr, "%s\n", with_errno("fragsim_cuda --serve: answering " + fifo).c_str());
  close(fd);
}

// Serves cases from DIR/requests until `quit` or a device error; run_case runs one case's
// command-line arguments and throws CaseError when it cannot. Returns the exit status.
static int serve(const std::string& dir_arg, const std::function<void(const std::vector<std::string>&)>& run_case) {
  signal(SIGPIPE, SIG_IGN);  // a client gone between open and write must not end the server
  // Absolute: the server enters each client's working directory.
  const std::string dir = std::filesystem::absolute(dir_arg).string();
  std::error_code error;
  std::filesystem::create_directories(dir, error);
  if (error) fail(STATUS_INPUT, "cannot create " + dir + ": " + error.message());
  const std::string requests = requests_fifo(dir);
  unlink(requests.c_str());
  if (mkfifo(requests.c_str(), 0600) != 0) fail(STATUS_INPUT, with_errno("cannot make " + requests));
  const int fd = open(requests.c_str(), O_RDWR);
  FILE* in = fd < 0 ? nullptr : fdopen(fd, "r");
  if (!in) fail(STATUS_INPUT, with_errno("cannot open " + requests));
  fprintf(stderr, "fragsim_cuda: serving %s\n", dir.c_str());
  int status = 0;
  char* buffer = nullptr;
  size_t capacity = 0;
  for (ssize_t length; status == 0 && (length = getline(&buffer, &capacity, in)) > 0;) {
    std::string line(buffer, length);
    if (line.back() == '\n') line.pop_back();
    if (line == "quit") break;
    const std::vector<std::string> fields = split_tabs(line);
    if (fields.size() < 3) {
      fprintf(stderr, "fragsim_cuda --serve: malformed request, ignored: %s\n", line.c_str());
      continue;
    }
    std::string answer = "ok";
    try {
      if (chdir(fields[1].c_str()) != 0) fail(STATUS_INPUT, with_errno("cannot enter " + fields[1]));
      run_case(std::vector<std::string>(fields.begin() + 2, fields.end()));
    } catch (const CaseError& e) {
      answer = std::string("error: ") + e.what();
      if (e.status == STATUS_DEVICE) status = e.status;
    } catch (const std::exception& e) {  // std::bad_alloc and the like: this case's, not the server's
      answer = std::string("error: ") + e.what();
    }
    if (answer != "ok") fprintf(stderr, "fragsim_cuda --serve: %s\n", answer.c_str());
    answer_client(fields[0], answer);
  }
  if (status) fprintf(stderr, "fragsim_cuda --serve: stopped after a device error\n");
  free(buffer);
  fclose(in);
  unlink(requests.c_str());
  return status;
}

// A file descriptor, closed when it goes out of scope.
struct Descriptor {
  int fd;
  explicit Descriptor(int fd) : fd(fd) {}
  ~Descriptor() {
    if (fd >= 0) close(fd);
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
};

// The client's answer FIFO in the server's directory, removed however the client ends (short of
// SIGKILL; the server removes one whose client is gone).
struct AnswerFifo {
  std::string path;
  explicit AnswerFifo(const std::string& dir) : path(dir + "/answer." + std::to_string(getpid())) {
    unlink(path.c_str());
    if (mkfifo(path.c_str(), 0600) != 0) fail(STATUS_INPUT, with_errno("cannot make " + path));
  }
  ~AnswerFifo() { unlink(path.c_str()); }
  AnswerFifo(const AnswerFifo&) = delete;
  AnswerFifo& operator=(const AnswerFifo&) = delete;
};

// `--client DIR [--timeout SECONDS] TRIANGLES OUTDIR [options]`: sends one case to the server at
// DIR and waits for its answer, at most SECONDS (default 60). Exit status 0 on `ok`; 1 with the
// server's message on stderr when the case failed or no answer came in time; STATUS_NO_SERVER
// when there is no server or it ended without answering.
static int client(const std::vector<std::string>& args) {
  signal(SIGPIPE, SIG_IGN);  // a server gone between open and write: EPIPE, reported below
  size_t first = 2;
  double timeout_s = 60;
  if (args.size() > 3 && args[2] == "--timeout") {
    timeout_s = atof(args[3].c_str());
    first = 4;
  }
  if (args.size() < first + 2 || !(timeout_s > 0))
    fail(STATUS_INPUT, "usage: fragsim_cuda --client DIR [--timeout SECONDS] TRIANGLES OUTDIR [options]");
  const std::string& dir = args[1];
  const auto no_server = [&](const std::string& why) {
    fprintf(stderr, "fragsim_cuda --client: %s\n", why.c_str());
    return STATUS_NO_SERVER;
  };
  const Descriptor requests(open(requests_fifo(dir).c_str(), O_WRONLY | O_NONBLOCK));
  if (requests.fd < 0) return no_server(with_errno("no server at " + dir));
  const AnswerFifo answer_fifo(std::filesystem::absolute(dir).string());
  // Nonblocking, so that opening does not wait for the server; read only once poll says so.
  const Descriptor answer(open(answer_fifo.path.c_str(), O_RDONLY | O_NONBLOCK));
  if (answer.fd < 0) fail(STATUS_INPUT, with_errno("cannot open " + answer_fifo.path));

  std::vector<std::string> fields = {answer_fifo.path, std::filesystem::current_path().string()};
  fields.insert(fields.end(), args.begin() + first, args.end());
  std::string line;
  for (const std::string& field : fields) {
    if (field.find_first_of("\t\n") != std::string::npos)
      fail(STATUS_INPUT, "a field with a tab or a newline cannot be sent: " + field);
    line += (line.empty() ? "" : "\t") + field;
  }
  line += "\n";
  // At most PIPE_BUF bytes are written whole: never interleaved with another client's request.
  if (line.size() > PIPE_BUF) fail(STATUS_INPUT, "the request is longer than " + std::to_string(PIPE_BUF) + " bytes");
  if (write(requests.fd, line.data(), line.size()) != (ssize_t)line.size())
    return no_server(with_errno("sending the request to " + dir));

  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  std::string reply;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      fprintf(stderr, "fragsim_cuda --client: no answer from %s within %g s\n", dir.c_str(), timeout_s);
      return 1;
    }
    // The requests FIFO reports POLLERR once no server holds it: the server died on this case.
    pollfd fds[2] = {{answer.fd, POLLIN, 0}, {requests.fd, 0, 0}};
    if (poll(fds, 2, (int)std::min<long long>(left.count(), 1000)) < 0 && errno != EINTR)
      fail(STATUS_INPUT, with_errno("poll"));
    if (fds[0].revents & (POLLIN | POLLHUP)) {
      char chunk[PIPE_BUF];
      const ssize_t n = read(answer.fd, chunk, sizeof chunk);
      if (n > 0) reply.append(chunk, n);
      if (n == 0 || reply.find('\n') != std::string::npos) break;  // the server wrote and closed
    } else if (fds[1].revents & POLLERR) {
      return no_server("the server at " + dir + " ended without answering");
    }
  }
  reply = reply.substr(0, reply.find('\n'));
  if (reply == "ok") return 0;
  fprintf(stderr, "fragsim_cuda --client: %s\n", reply.empty() ? "an empty answer" : reply.c_str());
  return 1;
}
