#include "telemetry/gateway/users.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>

namespace plantscale::telemetry::gateway {
namespace {

namespace fs = std::filesystem;

class GatewayUsers : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("plantscale_users_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    file_ = dir_ / "users.yaml";
  }
  void TearDown() override { fs::remove_all(dir_); }
  void Write(const std::string& text,
             fs::perms mode = fs::perms::owner_read | fs::perms::owner_write) {
    std::ofstream(file_) << text;
    fs::permissions(file_, mode);
  }
  std::string ErrorReading() {
    try {
      ReadUsers(file_);
    } catch (const UsersError& e) {
      return e.what();
    }
    return "(read)";
  }
  fs::path dir_;
  fs::path file_;
};

TEST_F(GatewayUsers, AddStoresOnlyASaltedHashInAFileOfMode0600) {
  const std::string token = AddUser(file_, "alice", Role::kOperator, false);
  EXPECT_EQ(token.size(), 64u);
  struct stat st {};
  ASSERT_EQ(::stat(file_.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  std::ifstream in(file_);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.find(token), std::string::npos);  // the token itself is not there
  const Users users = ReadUsers(file_);
  ASSERT_EQ(users.users.size(), 1u);
  EXPECT_EQ(users.users[0].name, "alice");
  EXPECT_EQ(users.users[0].role, Role::kOperator);
  const User* who = Authenticate(users, token);
  ASSERT_NE(who, nullptr);
  EXPECT_EQ(who->name, "alice");
}

TEST_F(GatewayUsers, WrongMissingOrAlteredTokensAreNobody) {
  const std::string a = AddUser(file_, "alice", Role::kOperator, false);
  const std::string b = AddUser(file_, "bob", Role::kViewer, false);
  const Users users = ReadUsers(file_);
  ASSERT_EQ(users.users.size(), 2u);
  EXPECT_EQ(Authenticate(users, b)->role, Role::kViewer);
  EXPECT_EQ(Authenticate(users, ""), nullptr);
  std::string altered = a;
  altered[10] = altered[10] == '0' ? '1' : '0';
  EXPECT_EQ(Authenticate(users, altered), nullptr);
  EXPECT_EQ(Authenticate(users, a.substr(0, 63)), nullptr);
  EXPECT_EQ(Authenticate(users, NewToken()), nullptr);
}

TEST_F(GatewayUsers, TheSameTokenHashesDifferentlyPerUser) {
  const User x = MakeUser("x", Role::kViewer, "secret");
  const User y = MakeUser("y", Role::kViewer, "secret");
  EXPECT_NE(x.salt, y.salt);
  EXPECT_NE(x.sha256, y.sha256);
}

TEST_F(GatewayUsers, ANameIsAddedOnceUnlessReplaced) {
  const std::string first = AddUser(file_, "alice", Role::kViewer, false);
  EXPECT_THROW(AddUser(file_, "alice", Role::kOperator, false), UsersError);
  const std::string second = AddUser(file_, "alice", Role::kOperator, true);
  const Users users = ReadUsers(file_);
  ASSERT_EQ(users.users.size(), 1u);
  EXPECT_EQ(Authenticate(users, first), nullptr);  // the old token no longer works
  EXPECT_EQ(Authenticate(users, second)->role, Role::kOperator);
  EXPECT_THROW(AddUser(file_, "a b", Role::kViewer, false), UsersError);
  EXPECT_THROW(AddUser(file_, "", Role::kViewer, false), UsersError);
}

TEST_F(GatewayUsers, BadFilesAreRefusedNamingFileAndReason) {
  AddUser(file_, "alice", Role::kViewer, false);
  fs::permissions(file_, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  std::string e = ErrorReading();
  EXPECT_NE(e.find(file_.string()), std::string::npos) << e;
  EXPECT_NE(e.find("mode 0640"), std::string::npos) << e;
  EXPECT_NE(e.find("chmod 600"), std::string::npos) << e;

  Write("users: [");
  EXPECT_NE(ErrorReading().find("not valid YAML"), std::string::npos);
  Write("people: []\n");
  EXPECT_NE(ErrorReading().find("no 'users:' list"), std::string::npos);
  Write("users: []\n");
  EXPECT_NE(ErrorReading().find("holds no user"), std::string::npos);
  const std::string salt(32, 'a');
  const std::string hash(64, 'b');
  Write("users:\n  - {name: a, role: admin, salt: " + salt + ", sha256: " + hash + "}\n");
  EXPECT_NE(ErrorReading().find("users[0].role: must be viewer or operator"), std::string::npos);
  Write("users:\n  - {name: a, role: viewer, salt: abc, sha256: " + hash + "}\n");
  EXPECT_NE(ErrorReading().find("users[0].salt"), std::string::npos);
  Write("users:\n  - {name: a, role: viewer, salt: " + salt + "}\n");
  EXPECT_NE(ErrorReading().find("users[0].sha256: missing"), std::string::npos);
  Write("users:\n  - {name: a, role: viewer, salt: " + salt + ", sha256: " + hash + "}\n" +
        "  - {name: a, role: viewer, salt: " + salt + ", sha256: " + hash + "}\n");
  EXPECT_NE(ErrorReading().find("user 'a' appears twice"), std::string::npos);
  fs::remove(file_);
  EXPECT_NE(ErrorReading().find("cannot read"), std::string::npos);
}

TEST_F(GatewayUsers, TokenComesFromTheQueryOrABearerHeader) {
  EXPECT_EQ(TokenFromRequest("/?token=abc123", ""), "abc123");
  EXPECT_EQ(TokenFromRequest("/x?a=1&token=ab%63&b=2", ""), "abc");
  EXPECT_EQ(TokenFromRequest("/", "Bearer  t0k "), "t0k");
  EXPECT_EQ(TokenFromRequest("/?token=q", "Bearer h"), "q");  // the query wins
  EXPECT_EQ(TokenFromRequest("/", "Basic dXNlcg=="), "");
  EXPECT_EQ(TokenFromRequest("/?tokens=x", ""), "");
  EXPECT_EQ(TokenFromRequest("/?token=", ""), "");
  EXPECT_EQ(TokenFromRequest("/?token=%4", ""), "%4");
}

TEST_F(GatewayUsers, RolesParse) {
  EXPECT_EQ(ParseRole("viewer"), Role::kViewer);
  EXPECT_EQ(ParseRole("operator"), Role::kOperator);
  EXPECT_EQ(ParseRole("root"), std::nullopt);
}

}  // namespace
}  // namespace plantscale::telemetry::gateway
