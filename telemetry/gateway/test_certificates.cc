#include "telemetry/gateway/test_certificates.h"

#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/x509.h>
#include <openssl/x509v3.h>

#include <cstdio>
#include <functional>
#include <memory>
#include <stdexcept>

namespace plantscale::telemetry::gateway {

namespace {

void Check(bool ok, const std::string& step) {
  if (!ok) throw std::runtime_error("MakeTestCertificate: " + step + " failed");
}

void AddExtension(X509* cert, int nid, const std::string& value) {
  X509V3_CTX ctx;
  X509V3_set_ctx_nodb(&ctx);
  X509V3_set_ctx(&ctx, cert, cert, nullptr, nullptr, 0);
  X509_EXTENSION* ext = X509V3_EXT_conf_nid(nullptr, &ctx, nid, value.c_str());
  Check(ext != nullptr, "extension " + value);
  const int added = X509_add_ext(cert, ext, -1);
  X509_EXTENSION_free(ext);
  Check(added == 1, "adding extension " + value);
}

void WritePem(const std::filesystem::path& file, const std::function<int(FILE*)>& write) {
  FILE* f = std::fopen(file.c_str(), "w");
  Check(f != nullptr, "opening " + file.string());
  const int ok = write(f);
  std::fclose(f);
  Check(ok == 1, "writing " + file.string());
}

}  // namespace

TestCertificate MakeTestCertificate(const std::filesystem::path& dir, const std::string& name,
                                    const std::string& common_name, const std::string& alt_names,
                                    long not_before_s, long not_after_s) {
  std::unique_ptr<EVP_PKEY, decltype(&EVP_PKEY_free)> key(EVP_EC_gen("P-256"), EVP_PKEY_free);
  Check(key != nullptr, "P-256 key");
  std::unique_ptr<X509, decltype(&X509_free)> cert(X509_new(), X509_free);
  Check(cert != nullptr, "X509_new");
  X509* x = cert.get();
  Check(X509_set_version(x, 2) == 1, "version");
  static long serial = 1;
  ASN1_INTEGER_set(X509_get_serialNumber(x), serial++);
  Check(X509_gmtime_adj(X509_getm_notBefore(x), not_before_s) != nullptr, "notBefore");
  Check(X509_gmtime_adj(X509_getm_notAfter(x), not_after_s) != nullptr, "notAfter");
  Check(X509_set_pubkey(x, key.get()) == 1, "public key");
  X509_NAME* subject = X509_get_subject_name(x);
  Check(X509_NAME_add_entry_by_txt(subject, "CN", MBSTRING_ASC,
                                   reinterpret_cast<const unsigned char*>(common_name.c_str()), -1, -1, 0) == 1,
        "CN");
  Check(X509_set_issuer_name(x, subject) == 1, "issuer");
  AddExtension(x, NID_basic_constraints, "critical,CA:TRUE");
  AddExtension(x, NID_subject_key_identifier, "hash");
  if (!alt_names.empty()) AddExtension(x, NID_subject_alt_name, alt_names);
  Check(X509_sign(x, key.get(), EVP_sha256()) > 0, "signing");
  TestCertificate out{dir / (name + ".cert.pem"), dir / (name + ".key.pem")};
  WritePem(out.cert, [&](FILE* f) { return PEM_write_X509(f, x); });
  WritePem(out.key, [&](FILE* f) {
    return PEM_write_PrivateKey(f, key.get(), nullptr, nullptr, 0, nullptr, nullptr);
  });
  return out;
}

}  // namespace plantscale::telemetry::gateway
