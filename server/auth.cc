#include "server/auth.h"

#include <grpcpp/server_context.h>
#include <grpcpp/support/server_interceptor.h>
#include <grpcpp/support/status.h>

#include <iostream>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "common/file_util.h"
#include "common/sha256.h"
#include "common/status_macros.h"
#include "server/status_util.h"

namespace sheetmesh::server {
namespace {

bool ValidTenant(absl::string_view t) {
  if (t.empty() || t.size() > 64 || !absl::ascii_isalnum(t[0])) return false;
  for (char c : t) {
    if (!absl::ascii_isalnum(c) && c != '.' && c != '_' && c != '-') return false;
  }
  return true;
}

}  // namespace

absl::Status Tenants::Add(const std::string& token, const std::string& tenant,
                          const std::string& where) {
  if (!ValidTenant(tenant)) {
    return absl::InvalidArgumentError(absl::StrCat(
        where, ": tenant '", tenant,
        "' must be 1 to 64 of the characters A-Z a-z 0-9 . _ -, the first a letter or digit"));
  }
  if (!tenant_of_hash_.emplace(Sha256Hex(token), tenant).second) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": this token is given twice"));
  }
  return absl::OkStatus();
}

absl::StatusOr<Tenants> Tenants::FromToken(const std::string& token) {
  Tenants t;
  if (token.empty()) return t;
  SM_RETURN_IF_ERROR(t.Add(token, kDefaultTenant, "--auth_token"));
  return t;
}

absl::StatusOr<Tenants> Tenants::FromFile(const std::string& path) {
  SM_ASSIGN_OR_RETURN(const std::string text, ReadFileToString(path));
  Tenants t;
  int line_no = 0;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    ++line_no;
    if (const size_t hash = line.find('#'); hash != absl::string_view::npos) {
      line = line.substr(0, hash);
    }
    line = absl::StripAsciiWhitespace(line);
    if (line.empty()) continue;
    const std::vector<std::string> words =
        absl::StrSplit(line, absl::ByAnyChar(" \t"), absl::SkipEmpty());
    const std::string where = absl::StrCat(path, " line ", line_no);
    if (words.size() > 2) {
      return absl::InvalidArgumentError(
          absl::StrCat(where, ": expected 'TOKEN [TENANT]', found ", words.size(), " words"));
    }
    SM_RETURN_IF_ERROR(t.Add(words[0], words.size() == 2 ? words[1] : kDefaultTenant, where));
  }
  if (t.open()) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, " holds no token (one 'TOKEN [TENANT]' per line)"));
  }
  return t;
}

grpc::Status Tenants::Authenticate(const grpc::ServerContextBase& context,
                                   std::string* tenant) const {
  tenant->clear();
  const auto& md = context.client_metadata();
  if (!worker_hashes_.empty()) {
    auto it = md.find("authorization");
    if (it != md.end()) {
      absl::string_view value(it->second.data(), it->second.size());
      if (absl::ConsumePrefix(&value, "Bearer ") && worker_hashes_.count(Sha256Hex(value))) {
        *tenant = kWorkerTenant;
        return grpc::Status::OK;
      }
    }
  }
  if (open()) {
    *tenant = kDefaultTenant;
    return grpc::Status::OK;
  }
  auto it = md.find("authorization");
  if (it != md.end()) {
    absl::string_view value(it->second.data(), it->second.size());
    if (absl::ConsumePrefix(&value, "Bearer ")) {
      auto found = tenant_of_hash_.find(Sha256Hex(value));
      if (found != tenant_of_hash_.end()) {
        *tenant = found->second;
        return grpc::Status::OK;
      }
    }
  }
  return ToGrpcStatus(absl::UnauthenticatedError(
      "missing or wrong bearer token (metadata 'authorization: Bearer <token>')"));
}

absl::Status Tenants::AddWorkerToken(const std::string& token, const std::string& where) {
  if (token.empty())
    return absl::InvalidArgumentError(absl::StrCat(where, ": the worker token is empty"));
  const std::string hash = Sha256Hex(token);
  if (tenant_of_hash_.count(hash)) {
    return absl::InvalidArgumentError(
        absl::StrCat(where, ": the worker token is also a tenant's token; give workers their own"));
  }
  worker_hashes_.insert(hash);
  return absl::OkStatus();
}

std::string ClientOf(const grpc::ServerContextBase& context, const std::string& tenant) {
  if (!tenant.empty()) return absl::StrCat("tenant:", tenant);
  // "ipv4:127.0.0.1:5678", "ipv6:[::1]:5678", "unix:/path": the address without the port.
  std::string peer = context.peer();
  if (!absl::StartsWith(peer, "unix:")) {
    if (const size_t colon = peer.rfind(':'); colon != std::string::npos && colon > 5) {
      peer.resize(colon);
    }
  }
  return absl::StrCat("peer:", peer);
}

namespace {

class GateInterceptor : public grpc::experimental::Interceptor {
 public:
  GateInterceptor(const Tenants* tenants, grpc::experimental::ServerRpcInfo* info)
      : tenants_(tenants), info_(info) {}

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(
            grpc::experimental::InterceptionHookPoints::POST_RECV_INITIAL_METADATA)) {
      std::string tenant;
      if (!tenants_->Authenticate(*info_->server_context(), &tenant).ok()) {
        std::cerr << "sheetmesh-server: " << info_->method() << " from "
                  << info_->server_context()->peer() << " without a known token: cancelled"
                  << std::endl;
        info_->server_context()->TryCancel();
      }
    }
    methods->Proceed();
  }

 private:
  const Tenants* tenants_;
  grpc::experimental::ServerRpcInfo* info_;
};

class GateFactory : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  explicit GateFactory(const Tenants* tenants) : tenants_(tenants) {}
  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override {
    const absl::string_view method = info->method();
    if (absl::StartsWith(method, "/sheetmesh.") ||
        absl::StartsWith(method, "/grpc.health.v1.Health/")) {
      return nullptr;
    }
    return new GateInterceptor(tenants_, info);
  }

 private:
  const Tenants* tenants_;
};

}  // namespace

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> TokenGate(
    const Tenants* tenants) {
  return std::make_unique<GateFactory>(tenants);
}

}  // namespace sheetmesh::server
