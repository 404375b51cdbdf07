// Who a call is. A server with no tokens is open: every caller is the tenant "default". A
// server with tokens requires "authorization: Bearer <token>" on every call but the
// health check, and the token names the caller's tenant: jobs, uploads and artifacts
// belong to a tenant, and one tenant never sees another's (job_service, blob_service).
#ifndef SHEETMESH_SERVER_AUTH_H_
#define SHEETMESH_SERVER_AUTH_H_

#include <map>
#include <memory>
#include <set>
#include <string>

#include "absl/status/statusor.h"

namespace grpc {
class ServerContextBase;
class Status;
namespace experimental {
class ServerInterceptorFactoryInterface;
}
}  // namespace grpc

namespace sheetmesh::server {

class Tenants {
 public:
  // The tenant a token without a tenant name belongs to (one --auth_token, or a token file
  // line with the token alone).
  static constexpr const char* kDefaultTenant = "default";

  // Open: no token needed.
  Tenants() = default;
  // One token, of the default tenant.
  static absl::StatusOr<Tenants> FromToken(const std::string& token);
  // A token file: one "TOKEN [TENANT]" per line; '#' starts a comment, blank lines are
  // skipped. kInvalidArgument naming the file and line for a malformed line, a tenant name
  // that is not [A-Za-z0-9._-]+, a token given twice, or a file without tokens.
  static absl::StatusOr<Tenants> FromFile(const std::string& path);

  // The identity of a remote worker's token (not a tenant name: those are [A-Za-z0-9._-]+).
  static constexpr const char* kWorkerTenant = "@workers";
  // A token remote workers present (WorkerService, and blob reads of any tenant's inputs).
  // kInvalidArgument for an empty one or one that is a tenant's too.
  absl::Status AddWorkerToken(const std::string& token, const std::string& where);
  bool has_worker_tokens() const { return !worker_hashes_.empty(); }

  bool open() const { return tenant_of_hash_.empty(); }
  // The tenant of the call ("default" on an open server). UNAUTHENTICATED without a known
  // token.
  grpc::Status Authenticate(const grpc::ServerContextBase& context, std::string* tenant) const;

 private:
  absl::Status Add(const std::string& token, const std::string& tenant, const std::string& where);
  // Tokens are kept by their SHA-256: a lookup compares hashes, not the secret itself.
  std::map<std::string, std::string> tenant_of_hash_;
  std::set<std::string> worker_hashes_;
};

// "tenant:<name>" for a tenant, else "peer:<address without port>": the unit that limits on
// open streams count per client.
std::string ClientOf(const grpc::ServerContextBase& context, const std::string& tenant);

// For a server with tokens: a gate in front of every service but the health check and
// sheetmesh's own (which check tokens themselves and answer UNAUTHENTICATED naming the
// problem). A call to another service, reflection among them, without a known token is
// cancelled before its handler reads anything (the caller sees CANCELLED: gRPC's
// interceptors cannot choose the status).
std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> TokenGate(
    const Tenants* tenants);

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_AUTH_H_
