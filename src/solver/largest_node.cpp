#include "largest_node.hpp"

namespace hypershape::solver {

LargestNode largest_node(const physics::Space& space, const PetscScalar* local, MPI_Comm comm,
                         std::vector<double>* norms2) {
  const int dim = space.dim();
  double best = -1;
  std::int64_t id = INT64_MAX;
  const physics::Space::OwnedNode* here = nullptr;
  if (norms2) norms2->clear();
  for (const auto& n : space.owned_nodes()) {
    double s = 0;
    for (int i = 0; i < dim; ++i) s += local[n.offset + i] * local[n.offset + i];
    if (norms2) norms2->push_back(s);
    if (s > best || (s == best && n.canonical < id)) best = s, id = n.canonical, here = &n;
  }
  LargestNode out;
  out.norm2 = best;
  MPI_Allreduce(MPI_IN_PLACE, &out.norm2, 1, MPI_DOUBLE, MPI_MAX, comm);
  std::int64_t gid = best == out.norm2 ? id : INT64_MAX;
  MPI_Allreduce(MPI_IN_PLACE, &gid, 1, MPI_INT64_T, MPI_MIN, comm);
  out.canonical = gid;
  out.here = best == out.norm2 && id == gid ? here : nullptr;  // else another rank owns the node
  return out;
}

}  // namespace hypershape::solver
