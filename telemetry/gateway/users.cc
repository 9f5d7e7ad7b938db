#include "telemetry/gateway/users.h"

#include <fcntl.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/rand.h>
#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

namespace plantscale::telemetry::gateway {

namespace {

namespace fs = std::filesystem;

std::string Hex(const uint8_t* data, size_t size) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string s;
  s.reserve(2 * size);
  for (size_t i = 0; i < size; ++i) {
    s += kHex[data[i] >> 4];
    s += kHex[data[i] & 15];
  }
  return s;
}

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

template <size_t N>
bool FromHex(const std::string& s, std::array<uint8_t, N>& out) {
  if (s.size() != 2 * N) return false;
  for (size_t i = 0; i < N; ++i) {
    const int hi = HexDigit(s[2 * i]);
    const int lo = HexDigit(s[2 * i + 1]);
    if (hi < 0 || lo < 0) return false;
    out[i] = static_cast<uint8_t>(hi * 16 + lo);
  }
  return true;
}

std::array<uint8_t, 32> SaltedHash(const std::array<uint8_t, kSaltBytes>& salt,
                                   std::string_view token) {
  std::array<uint8_t, 32> out{};
  EVP_MD_CTX* ctx = EVP_MD_CTX_new();
  unsigned int size = 0;
  const bool ok = ctx && EVP_DigestInit_ex(ctx, EVP_sha256(), nullptr) == 1 &&
                  EVP_DigestUpdate(ctx, salt.data(), salt.size()) == 1 &&
                  EVP_DigestUpdate(ctx, token.data(), token.size()) == 1 &&
                  EVP_DigestFinal_ex(ctx, out.data(), &size) == 1 && size == out.size();
  EVP_MD_CTX_free(ctx);
  if (!ok) throw UsersError("OpenSSL SHA-256 failed");
  return out;
}

void RandomBytes(uint8_t* out, size_t n) {
  if (RAND_bytes(out, static_cast<int>(n)) != 1) throw UsersError("OpenSSL RAND_bytes failed");
}

[[noreturn]] void Fail(const fs::path& file, const std::string& reason) {
  throw UsersError("users file " + file.string() + ": " + reason);
}
[[noreturn]] void FailWrite(const fs::path& file, const std::string& reason) {
  throw UsersWriteError("users file " + file.string() + ": " + reason);
}

void CheckMode(const fs::path& file) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0)
    Fail(file, std::string("cannot read: ") + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) Fail(file, "not a regular file");
  if ((st.st_mode & 077) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", st.st_mode & 07777);
    Fail(file, std::string("has mode ") + mode +
                   ": group and others must have no access (mode 0600: chmod 600 " + file.string() +
                   ")");
  }
}

std::string Field(const YAML::Node& node, const char* key, const fs::path& file, size_t index) {
  const YAML::Node v = node[key];
  if (!v || !v.IsScalar()) {
    Fail(file, "users[" + std::to_string(index) + "]." + key + ": missing or not a string");
  }
  return v.as<std::string>();
}

}  // namespace

const char* RoleName(Role role) { return role == Role::kOperator ? "operator" : "viewer"; }

std::optional<Role> ParseRole(std::string_view name) {
  if (name == "viewer") return Role::kViewer;
  if (name == "operator") return Role::kOperator;
  return std::nullopt;
}

bool ValidUserName(std::string_view name) {
  if (name.empty() || name.size() > 64) return false;
  for (const char c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == '@' || c == '-';
    if (!ok) return false;
  }
  return true;
}

std::string NewToken() {
  std::array<uint8_t, kTokenBytes> bytes{};
  RandomBytes(bytes.data(), bytes.size());
  return Hex(bytes.data(), bytes.size());
}

User MakeUser(const std::string& name, Role role, std::string_view token) {
  User u;
  u.name = name;
  u.role = role;
  RandomBytes(u.salt.data(), u.salt.size());
  u.sha256 = SaltedHash(u.salt, token);
  return u;
}

Users ReadUsers(const fs::path& file) {
  CheckMode(file);
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::Exception& e) {
    Fail(file, std::string("not valid YAML: ") + e.what());
  }
  const YAML::Node list = root.IsMap() ? root["users"] : YAML::Node();
  if (!list || !list.IsSequence())
    Fail(file, "no 'users:' list (make one with plantscale users add)");
  Users users;
  users.file = file;
  std::set<std::string> names;
  try {
    for (size_t i = 0; i < list.size(); ++i) {
      const YAML::Node n = list[i];
      if (!n.IsMap()) Fail(file, "users[" + std::to_string(i) + "]: not a mapping");
      User u;
      u.name = Field(n, "name", file, i);
      if (!ValidUserName(u.name))
        Fail(file, "users[" + std::to_string(i) + "].name: '" + u.name +
                       "' is not 1-64 of A-Z a-z 0-9 . _ @ -");
      const auto role = ParseRole(Field(n, "role", file, i));
      if (!role) Fail(file, "users[" + std::to_string(i) + "].role: must be viewer or operator");
      u.role = *role;
      if (!FromHex(Field(n, "salt", file, i), u.salt)) {
        Fail(file, "users[" + std::to_string(i) + "].salt: must be " +
                       std::to_string(2 * kSaltBytes) + " hex digits");
      }
      if (!FromHex(Field(n, "sha256", file, i), u.sha256)) {
        Fail(file, "users[" + std::to_string(i) + "].sha256: must be 64 hex digits");
      }
      if (!names.insert(u.name).second) Fail(file, "user '" + u.name + "' appears twice");
      users.users.push_back(std::move(u));
    }
  } catch (const YAML::Exception& e) {
    Fail(file, std::string("not valid YAML: ") + e.what());
  }
  if (users.users.empty()) Fail(file, "holds no user (add one with plantscale users add)");
  return users;
}

void WriteUsers(const Users& users, const fs::path& file) {
  std::ostringstream out;
  out << "# plantscale gateway users: written by `plantscale users add`; tokens are kept only as\n"
         "# SHA-256(salt || token). Keep this file mode 0600.\n"
         "users:\n";
  for (const User& u : users.users) {
    out << "  - name: " << u.name << "\n    role: " << RoleName(u.role)
        << "\n    salt: " << Hex(u.salt.data(), u.salt.size())
        << "\n    sha256: " << Hex(u.sha256.data(), u.sha256.size()) << "\n";
  }
  const std::string text = out.str();
  const fs::path tmp = file.string() + ".tmp";
  ::unlink(tmp.c_str());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0)
    FailWrite(file, std::string("cannot write ") + tmp.string() + ": " + std::strerror(errno));
  const ssize_t written = ::write(fd, text.data(), text.size());
  const bool ok = written == static_cast<ssize_t>(text.size()) && ::fsync(fd) == 0;
  ::close(fd);
  if (!ok || ::rename(tmp.c_str(), file.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    FailWrite(file, "cannot write: " + why);
  }
}

std::string AddUser(const fs::path& file, const std::string& name, Role role, bool replace) {
  if (!ValidUserName(name)) {
    throw UsersError("user name '" + name + "' is not 1-64 of A-Z a-z 0-9 . _ @ -");
  }
  Users users;
  users.file = file;
  std::error_code ec;
  if (fs::exists(file, ec)) users = ReadUsers(file);
  const std::string token = NewToken();
  User user = MakeUser(name, role, token);
  bool replaced = false;
  for (User& u : users.users) {
    if (u.name != name) continue;
    if (!replace) Fail(file, "user '" + name + "' exists (--replace gives it a new token)");
    u = user;
    replaced = true;
  }
  if (!replaced) users.users.push_back(std::move(user));
  WriteUsers(users, file);
  return token;
}

const User* Authenticate(const Users& users, std::string_view token) {
  const User* found = nullptr;
  for (const User& u : users.users) {
    const std::array<uint8_t, 32> h = SaltedHash(u.salt, token);
    const bool match = CRYPTO_memcmp(h.data(), u.sha256.data(), h.size()) == 0;
    if (match && !found) found = &u;
  }
  return found;
}

std::string TokenFromRequest(std::string_view target, std::string_view authorization) {
  const size_t q = target.find('?');
  if (q != std::string_view::npos) {
    std::string_view query = target.substr(q + 1);
    while (!query.empty()) {
      const size_t amp = query.find('&');
      const std::string_view pair = query.substr(0, amp);
      query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
      if (pair.substr(0, 6) != "token=") continue;
      std::string value;
      const std::string_view raw = pair.substr(6);
      for (size_t i = 0; i < raw.size(); ++i) {
        if (raw[i] == '%' && i + 2 < raw.size() && HexDigit(raw[i + 1]) >= 0 &&
            HexDigit(raw[i + 2]) >= 0) {
          value += static_cast<char>(HexDigit(raw[i + 1]) * 16 + HexDigit(raw[i + 2]));
          i += 2;
        } else {
          value += raw[i] == '+' ? ' ' : raw[i];
        }
      }
      if (!value.empty()) return value;
    }
  }
  constexpr std::string_view kBearer = "Bearer ";
  if (authorization.size() > kBearer.size() && authorization.substr(0, kBearer.size()) == kBearer) {
    std::string_view t = authorization.substr(kBearer.size());
    while (!t.empty() && t.front() == ' ') t.remove_prefix(1);
    while (!t.empty() && (t.back() == ' ' || t.back() == '\t')) t.remove_suffix(1);
    return std::string(t);
  }
  return {};
}

}  // namespace plantscale::telemetry::gateway
