#pragma once
// Who may connect to the gateway: USERS.yaml holds, per user, a name, a role
// and a salted SHA-256 of the user's token, never the token itself
// (`plantscale users add` prints the token once). The file must be mode
// 0600 (or 0400) like the command key; the gateway refuses it otherwise.
//
//   # plantscale gateway users: written by `plantscale users add`
//   users:
//     - name: alice
//       role: operator          # viewer: sees; operator: may also send commands
//       salt: 5f1c...           # 16 random bytes, hex
//       sha256: 9a0b...         # SHA-256(salt || token), hex
//
// A token is 32 random bytes (OpenSSL's RAND_bytes) as 64 hex digits.
// Errors throw UsersError with one line naming the file and the reason.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace plantscale::telemetry::gateway {

class UsersError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// The users file could not be written (an I/O failure, not bad input).
class UsersWriteError : public UsersError {
 public:
  using UsersError::UsersError;
};

enum class Role { kViewer, kOperator };
const char* RoleName(Role role);
std::optional<Role> ParseRole(std::string_view name);

inline constexpr size_t kTokenBytes = 32;
inline constexpr size_t kSaltBytes = 16;

struct User {
  std::string name;  // 1–64 of [A-Za-z0-9._@-]
  Role role = Role::kViewer;
  std::array<uint8_t, kSaltBytes> salt{};
  std::array<uint8_t, 32> sha256{};
};

struct Users {
  std::vector<User> users;
  std::filesystem::path file;  // where they were read from, for messages
};

bool ValidUserName(std::string_view name);

// A new random token: 64 hex digits.
std::string NewToken();
// A user whose token is `token`, with a fresh random salt.
User MakeUser(const std::string& name, Role role, std::string_view token);

// Reads USERS.yaml. Throws UsersError naming the file when it cannot be
// read, is not a regular file, has group or other permission bits (the
// message gives its mode and asks for 0600), is not the YAML above, names a
// user twice or holds no user.
Users ReadUsers(const std::filesystem::path& file);
// Writes the users to `file` (mode 0600) through a temporary file renamed
// over it. Throws UsersWriteError when it cannot.
void WriteUsers(const Users& users, const std::filesystem::path& file);
// Adds a user with a new token to `file` (created when missing) and returns
// the token. Throws UsersError for a bad name, or a name already there
// unless `replace` (a new token for the same name).
std::string AddUser(const std::filesystem::path& file, const std::string& name, Role role,
                    bool replace);

// The user whose token this is, or null. Every user's hash is computed and
// compared in constant time, so the time taken says nothing about which.
const User* Authenticate(const Users& users, std::string_view token);

// The token of an HTTP upgrade request: `token=` in the target's query
// (percent-decoded), else an `Authorization: Bearer TOKEN` header value.
// Empty when neither holds one.
std::string TokenFromRequest(std::string_view target, std::string_view authorization);

}  // namespace plantscale::telemetry::gateway
