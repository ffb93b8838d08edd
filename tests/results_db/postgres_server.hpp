// A PostgreSQL server of a test's (or bench's) own: a new cluster in a temporary folder, on a
// free port and a Unix socket in that folder, stopped when the object goes. PostgreSQL refuses to
// run as root, so under root (tests run as root in CI) its programs run as `nobody`, the folder
// theirs.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <grp.h>
#include <libpq-fe.h>
#include <netinet/in.h>
#include <pwd.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace robotperf::test_support {

// The newest /usr/lib/postgresql/<version>/bin that holds the server's programs; empty when
// there is none (the PostgreSQL tests are then skipped).
inline std::filesystem::path postgres_bin_dir() {
  namespace fs = std::filesystem;
  std::filesystem::path newest;
  int newest_version = -1;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/usr/lib/postgresql", ec)) {
    const fs::path bin = e.path() / "bin";
    int version = -1;
    try {
      version = std::stoi(e.path().filename().string());
    } catch (const std::exception&) {
      continue;
    }
    if (version > newest_version && fs::exists(bin / "initdb") && fs::exists(bin / "pg_ctl") &&
        fs::exists(bin / "postgres")) {
      newest = bin;
      newest_version = version;
    }
  }
  return newest;
}

class PostgresServer {
 public:
  // The cluster's superuser: over the Unix socket without a password (trust), over TCP with
  // password() (scram-sha-256).
  static constexpr const char* kUser = "robotperf";

  // durable: fsync on, as a lab's server has it (the bench); tests go without.
  explicit PostgresServer(bool durable = false) : bin_(postgres_bin_dir()) {
    if (bin_.empty()) throw std::runtime_error("no PostgreSQL server in /usr/lib/postgresql/*/bin");
    if (geteuid() == 0) {
      const passwd* nobody = getpwnam("nobody");
      const group* nogroup = getgrnam("nogroup");
      if (nobody == nullptr)
        throw std::runtime_error("running as root, and no user nobody to run PostgreSQL as");
      uid_ = nobody->pw_uid;
      gid_ = nogroup ? nogroup->gr_gid : nobody->pw_gid;
    }
    // /tmp, not $TMPDIR: a Unix socket's path is limited to about 100 characters.
    std::string folder = "/tmp/robotperf-pg-XXXXXX";
    if (mkdtemp(folder.data()) == nullptr) throw std::runtime_error("cannot make " + folder);
    dir_ = folder;
    std::random_device random;
    password_ = "pw-" + std::to_string(random()) + std::to_string(random());
    std::ofstream(dir_ / "pwfile") << password_ << "\n";
    own(dir_);
    own(dir_ / "pwfile");
    run({(bin_ / "initdb").string(), "-D", data().string(), "-U", kUser,
         "--pwfile=" + (dir_ / "pwfile").string(), "--auth-local=trust",
         "--auth-host=scram-sha-256", "-E", "UTF8", "--locale=C", "--no-sync", "--no-instructions"},
        "initdb");
    std::filesystem::remove(dir_ / "pwfile");
    // Another process may take the port between its choice and the server's start: another one.
    for (int attempt = 0;; ++attempt) {
      port_ = free_port();
      const std::string settings = "-p " + std::to_string(port_) + " -k " + dir_.string() +
                                   " -c listen_addresses=127.0.0.1" +
                                   (durable ? "" : " -c fsync=off -c synchronous_commit=off");
      try {
        run({(bin_ / "pg_ctl").string(), "-D", data().string(), "-l",
             (dir_ / "server.log").string(), "-w", "-t", "60", "-s", "-o", settings, "start"},
            "pg_ctl start");
        break;
      } catch (const std::runtime_error&) {
        if (attempt == 2) {
          std::filesystem::remove_all(dir_);
          throw;
        }
      }
    }
  }

  ~PostgresServer() {
    try {
      run({(bin_ / "pg_ctl").string(), "-D", data().string(), "-m", "immediate", "-w", "-s",
           "stop"},
          "pg_ctl stop");
    } catch (const std::exception&) {
      // Stopped already, or never started: the folder goes all the same.
    }
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  PostgresServer(const PostgresServer&) = delete;
  PostgresServer& operator=(const PostgresServer&) = delete;

  int port() const { return port_; }
  const std::string& password() const { return password_; }
  // The server's temporary folder: files a test makes there go with it.
  const std::filesystem::path& dir() const { return dir_; }

  // The database `name` over the Unix socket (no password) and over TCP (password required).
  std::string socket_url(const std::string& name) const {
    std::string host;
    for (char c : dir_.string()) host += c == '/' ? std::string("%2F") : std::string(1, c);
    return std::string("postgresql://") + kUser + "@" + host + ":" + std::to_string(port_) + "/" +
           name;
  }
  std::string tcp_url(const std::string& name) const {
    return std::string("postgresql://") + kUser + "@127.0.0.1:" + std::to_string(port_) + "/" +
           name;
  }

  void create_database(const std::string& name) const {
    query("postgres", "CREATE DATABASE \"" + name + "\"");
  }

  // The rows `sql` returns in the database `name`, each value as text ("" for NULL).
  std::vector<std::vector<std::string>> query(const std::string& name,
                                              const std::string& sql) const {
    std::unique_ptr<PGconn, decltype(&PQfinish)> c(PQconnectdb(socket_url(name).c_str()),
                                                   &PQfinish);
    if (PQstatus(c.get()) != CONNECTION_OK)
      throw std::runtime_error("cannot connect: " + std::string(PQerrorMessage(c.get())));
    std::unique_ptr<PGresult, decltype(&PQclear)> r(PQexec(c.get(), sql.c_str()), &PQclear);
    const ExecStatusType status = PQresultStatus(r.get());
    if (status != PGRES_COMMAND_OK && status != PGRES_TUPLES_OK)
      throw std::runtime_error(sql + ": " + PQresultErrorMessage(r.get()));
    std::vector<std::vector<std::string>> rows(static_cast<std::size_t>(PQntuples(r.get())));
    for (int row = 0; row < PQntuples(r.get()); ++row) {
      for (int column = 0; column < PQnfields(r.get()); ++column)
        rows[static_cast<std::size_t>(row)].emplace_back(PQgetvalue(r.get(), row, column));
    }
    return rows;
  }

 private:
  std::filesystem::path data() const { return dir_ / "data"; }

  void own(const std::filesystem::path& path) const {
    if (uid_ != 0 && chown(path.c_str(), uid_, gid_) != 0)
      throw std::runtime_error("cannot give " + path.string() + " to nobody");
  }

  static int free_port() {
    const int s = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t size = sizeof address;
    int port = 0;
    if (bind(s, reinterpret_cast<sockaddr*>(&address), size) == 0 &&
        getsockname(s, reinterpret_cast<sockaddr*>(&address), &size) == 0)
      port = ntohs(address.sin_port);
    close(s);
    if (port == 0) throw std::runtime_error("no free TCP port on 127.0.0.1");
    return port;
  }

  // Runs a server program (as nobody under root) in the server's folder, its output to a log
  // there; throws with that log when it fails.
  void run(const std::vector<std::string>& argv, const std::string& what) const {
    const std::filesystem::path log = dir_ / "command.log";
    const int out = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    const pid_t pid = fork();
    if (pid == 0) {
      dup2(out, STDOUT_FILENO);
      dup2(out, STDERR_FILENO);
      if (uid_ != 0 && (setgroups(0, nullptr) != 0 || setgid(gid_) != 0 || setuid(uid_) != 0))
        _exit(126);
      if (chdir(dir_.c_str()) != 0) _exit(126);
      execv(args[0], args.data());
      _exit(127);
    }
    close(out);
    int status = 0;
    if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status) ||
        WEXITSTATUS(status) != 0) {
      std::ifstream in(log);
      std::stringstream text;
      text << in.rdbuf();
      std::ifstream server(dir_ / "server.log");
      text << server.rdbuf();
      throw std::runtime_error(what + " failed: " + text.str());
    }
  }

  std::filesystem::path bin_;
  std::filesystem::path dir_;
  uid_t uid_ = 0;
  gid_t gid_ = 0;
  int port_ = 0;
  std::string password_;
};

}  // namespace robotperf::test_support
