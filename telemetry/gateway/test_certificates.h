#pragma once
// Certificates for the gateway's TLS tests, made with OpenSSL's API at test
// time (no files in the repository, no openssl command line): self-signed
// P-256, with the subjectAltNames and the validity window a test needs, so
// that expired, not-yet-valid and wrong-name certificates can be served by a
// real gateway and refused by a real client.
#include <filesystem>
#include <string>

namespace plantscale::telemetry::gateway {

struct TestCertificate {
  std::filesystem::path cert;  // PEM certificate
  std::filesystem::path key;   // PEM private key (unencrypted)
};

// Writes DIR/NAME.cert.pem and DIR/NAME.key.pem: subject CN=`common_name`,
// subjectAltName `alt_names` (OpenSSL's syntax, "IP:127.0.0.1,DNS:localhost";
// empty: none), valid from now + not_before_s to now + not_after_s (seconds,
// negative in the past). Throws std::runtime_error naming the step that failed.
TestCertificate MakeTestCertificate(const std::filesystem::path& dir, const std::string& name,
                                    const std::string& common_name, const std::string& alt_names,
                                    long not_before_s, long not_after_s);

}  // namespace plantscale::telemetry::gateway
