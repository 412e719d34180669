#!/usr/bin/python3
"""A baseline users know: the same scene solved by hypershape and by DOLFINx, side by side.

    scripts/bench_dolfinx.py [SCENE.yaml] [--case DEGREE:H ...] [--targets 0.1,0.2,...]
                             [--repeat N] [--rounds R] [--hypershape build/hypershape]

For each case (element degree, mesh size h; default the disk at P1 h 0.04 and P2 h 0.08) it
1. runs `hypershape solve SCENE --targets T1,... --repeat N+1` (the scene with mesh.h and
   mesh.degree overridden): every target solved in turn, N+1 times over, each load case from
   rest (u = 0) on one problem and solver, its own seconds per load case in /timings/;
2. reads hypershape's mesh from that output (vertices and cells; the P2 nodes are the edge
   midpoints of the straight-sided cells, as DOLFINx's P2 nodes are) into DOLFINx, and builds
   the same discretisation: vector Lagrange of the same degree, the same cell quadrature
   degree (2 degree - 1) and facet quadrature degree (2 degree + 2) as hypershape's
   SpaceOptions defaults, the seed's Neo-Hookean energy (plane strain in 2D), the same clamp
   (the boundary facets whose vertices all lie within r of p_D, all their nodes fixed), the
   Gaussian traction alpha g phi(x - p_N) / I_N on the other boundary facets with I_N by the
   same facet rule, residual and Jacobian by UFL `derivative` of the energy;
3. checks that the two agree: DOLFINx solved at hypershape's alpha must give hypershape's
   max|u| and nodal field (printed: relative differences);
4. times DOLFINx the way the seed paper solves: per load case, from rest, a proportional
   guess alpha_0 = target / max|K(0)^-1 f_ext| (K(0) factorised once per mesh), then a secant
   search on alpha until |max|u| / target - 1| <= 1e-3, each alpha solved by DOLFINx's
   NewtonSolver (MUMPS LU, convergence ||R|| <= 1e-9 ||alpha f_ext|| as hypershape) from the
   previous converged state, with adaptive load continuation (halve the increment after a
   failed Newton solve, double it after a success) where a full step fails;
5. prints a markdown table and writes results/bench_dolfinx.json (every load case of both).

Timings are warm on both sides: the first pass over the targets is discarded (hypershape's
pays the symbolic factorisation and K(0); DOLFINx's JIT and set-up are outside any timing),
and the median over the remaining N passes is reported. The two sides take turns `--rounds`
times (a hypershape process, then DOLFINx's passes, ...), so that a change in the load of a
shared host falls on both. Each side's seconds per load case
run from u = 0 to the converged target: the nonlinear solves, assembly, factorisations and
the alpha search; not the mesh, the function space, the forms or the output.

Optional and not part of CI: it needs Debian's python3-dolfinx (DOLFINx 0.5.2) and runs
with /usr/bin/python3. Single process (1 MPI rank on each side); set OMP/BLAS threads to 1.
"""
import argparse
import json
import os
import re
import shlex
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def in_repo(path):
    """The path relative to the repository where it lies inside it (the JSON names no machine)."""
    p = path.resolve()
    return str(p.relative_to(ROOT)) if p.is_relative_to(ROOT) else str(path)

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
    os.environ.setdefault(var, "1")


def import_dolfinx():
    """Imports DOLFINx and friends, or exits with a message saying how to get them."""
    try:
        import dolfinx  # noqa: F401
        import dolfinx.fem.petsc  # noqa: F401
        import dolfinx.nls.petsc  # noqa: F401
        import ufl  # noqa: F401
        from mpi4py import MPI  # noqa: F401
        from petsc4py import PETSc  # noqa: F401
    except ImportError as e:
        # Debian's DOLFINx lives in /usr/bin/python3's path only (not a venv's or pyenv's).
        if os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") and \
                os.path.exists("/usr/bin/python3") and not os.environ.get("BENCH_DOLFINX_REEXEC"):
            os.environ["BENCH_DOLFINX_REEXEC"] = "1"
            os.execv("/usr/bin/python3", ["/usr/bin/python3", __file__] + sys.argv[1:])
        sys.exit(f"bench_dolfinx: DOLFINx is not available ({e}).\n"
                 "This optional benchmark needs Debian's python3-dolfinx (DOLFINx 0.5.2):\n"
                 "    apt-get install -y --no-install-recommends python3-dolfinx\n"
                 "and runs with /usr/bin/python3.")
    try:
        import h5py  # noqa: F401
        import numpy  # noqa: F401
        import yaml  # noqa: F401
    except ImportError as e:
        sys.exit(f"bench_dolfinx: {e}; install python3-h5py python3-numpy python3-yaml")


# ----------------------------------------------------------------------------------------------
# hypershape side


def supports_targets(exe):
    """Whether this hypershape has `solve --targets/--repeat` (several load cases per process)."""
    r = subprocess.run([str(exe), "solve", "--help"], capture_output=True, text=True)
    return "--targets" in r.stdout + r.stderr


def run_hypershape(exe, scene, degree, h, target, workdir, name, args):
    """Writes the scene with mesh.h/degree overridden and load.target = target, runs
    `hypershape solve SCENE -o OUT ARGS`, returns (output file, stdout)."""
    import yaml
    s = dict(scene)
    s["mesh"] = dict(s.get("mesh") or {})
    s["mesh"]["h"] = h
    s["mesh"]["degree"] = degree
    s["load"] = {"target": target}
    scene_path = workdir / f"{name}.yaml"
    scene_path.write_text(yaml.safe_dump(s, default_flow_style=None, sort_keys=False))
    out = workdir / f"{name}.h5"
    cmd = [str(exe), "solve", str(scene_path), "-o", str(out)] + list(args)
    print("$ " + " ".join(cmd), flush=True)
    r = subprocess.run(cmd, capture_output=True, text=True)
    sys.stdout.write(r.stdout)
    if r.returncode != 0:
        sys.stderr.write(r.stderr)
        sys.exit(f"bench_dolfinx: hypershape failed (exit {r.returncode})")
    return out, r.stdout


def read_hypershape(path):
    import h5py
    import numpy as np
    with h5py.File(path, "r") as f:
        out = {k: f["timings"][k][:] for k in f["timings"]} if "timings" in f else {}
        out["nodes"] = f["mesh/nodes"][:]
        out["cells"] = f["mesh/cells"][:].astype(np.int64)
        out["u_last"] = f["fields/displacement"][:]
        out["n_vertices"] = int(f.attrs["n_vertices"])
        out["degree"] = int(f.attrs["degree"])
        out["attrs"] = {k: f.attrs[k] for k in ("target", "alpha", "max_displacement", "converged",
                                                 "newton_iterations") if k in f.attrs}
    return out


def hypershape_side(exe, scene, degree, h, targets, passes, workdir, name, extra, multi):
    """hypershape's load cases: `passes` passes over `targets`, each from rest. With `multi`
    (`solve --targets --repeat`), one process and its own per-load-case seconds; otherwise
    (a build without them) one process per load case, timed by its `solve` phase (which then
    also pays the symbolic factorisation, K(0) and max|u|: cold, slower)."""
    import numpy as np
    if multi:
        out, _ = run_hypershape(exe, scene, degree, h, targets[0], workdir, name,
                                ["--targets", ",".join(f"{t:.17g}" for t in targets),
                                 "--repeat", str(passes)] + list(extra))
        return read_hypershape(out)
    cols = {k: [] for k in ("target", "alpha", "max_displacement", "converged", "newton_iterations", "seconds")}
    for _ in range(passes):
        for T in targets:
            out, text = run_hypershape(exe, scene, degree, h, T, workdir, name, extra)
            hs = read_hypershape(out)
            m = re.search(r" solve ([0-9.]+)s", text)
            if not m:
                sys.exit("bench_dolfinx: no 'solve N.NNNs' phase time in hypershape's summary line")
            cols["seconds"].append(float(m.group(1)))
            for k in ("target", "alpha", "max_displacement", "converged", "newton_iterations"):
                cols[k].append(float(hs["attrs"][k]))
    hs.update({k: np.array(v) for k, v in cols.items()})
    return hs


def load_cases(hs):
    """hypershape's load cases as a list of records."""
    return [{"target": float(hs["target"][i]), "alpha": float(hs["alpha"][i]),
             "max_displacement": float(hs["max_displacement"][i]), "seconds": float(hs["seconds"][i]),
             "newton_iterations": int(hs["newton_iterations"][i]), "converged": bool(hs["converged"][i])}
            for i in range(len(hs["seconds"]))]


# ----------------------------------------------------------------------------------------------
# DOLFINx side


# hypershape's quadrature (src/physics/space.cpp): PETSc's minimal symmetric simplex rules
# (PetscDTSimplexQuadrature(dim, degree, PETSCDTSIMPLEXQUAD_MINSYM)) of exactness 2 p - 1 on
# cells and 2 p + 2 on facets, printed from PETSc 3.18 and mapped to Basix's reference simplex.
# On intervals they are Gauss-Legendre, as Basix's default; on triangles and tetrahedra Basix's
# default rules of the same degree have other points (on the disk at P2 h 0.08 that moved
# max|u| by 5e-4), so the cell and the 3D facet integrals get these as custom rules.
MINSYM = {  # (dim, degree): [(reference point (Basix's simplex), weight), ...]
    (2, 1): [
        ((0.33333333333333337, 0.33333333333333337), 0.5),
    ],
    (2, 3): [
        ((0.4459484909159649, 0.4459484909159649), 0.11169079483900574),
        ((0.09157621350977074, 0.09157621350977074), 0.054975871827660935),
        ((0.4459484909159649, 0.10810301816807022), 0.11169079483900574),
        ((0.09157621350977074, 0.8168475729804585), 0.054975871827660935),
        ((0.10810301816807022, 0.4459484909159649), 0.11169079483900574),
        ((0.8168475729804585, 0.09157621350977074), 0.054975871827660935),
    ],
    (2, 6): [
        ((0.06308901449150223, 0.06308901449150223), 0.02542245318510341),
        ((0.24928674517091043, 0.24928674517091043), 0.058393137863189684),
        ((0.06308901449150223, 0.8738219710169955), 0.02542245318510341),
        ((0.24928674517091043, 0.5014265096581791), 0.058393137863189684),
        ((0.8738219710169955, 0.06308901449150223), 0.02542245318510341),
        ((0.5014265096581791, 0.24928674517091043), 0.058393137863189684),
        ((0.05314504984481694, 0.6365024991213987), 0.041425537809186785),
        ((0.05314504984481694, 0.3103524510337844), 0.041425537809186785),
        ((0.6365024991213987, 0.05314504984481694), 0.041425537809186785),
        ((0.3103524510337844, 0.05314504984481694), 0.041425537809186785),
        ((0.3103524510337844, 0.6365024991213987), 0.041425537809186785),
        ((0.6365024991213987, 0.3103524510337844), 0.041425537809186785),
    ],
    (3, 1): [
        ((0.25, 0.25, 0.25), 0.16666666666666666),
    ],
    (3, 3): [
        ((0.328681146665349, 0.328681146665349, 0.328681146665349), 0.02124855192625107),
        ((0.1119207275092915, 0.1119207275092915, 0.1119207275092915), 0.020418114740415595),
        ((0.328681146665349, 0.328681146665349, 0.013956560003953067), 0.02124855192625107),
        ((0.1119207275092915, 0.1119207275092915, 0.6642378174721254), 0.020418114740415595),
        ((0.328681146665349, 0.013956560003953067, 0.328681146665349), 0.02124855192625107),
        ((0.1119207275092915, 0.6642378174721254, 0.1119207275092915), 0.020418114740415595),
        ((0.013956560003953067, 0.328681146665349, 0.328681146665349), 0.02124855192625107),
        ((0.6642378174721254, 0.1119207275092915, 0.1119207275092915), 0.020418114740415595),
    ],
}
MINSYM[(2, 4)] = MINSYM[(2, 3)]  # PETSc 3.18 gives the same 6-point rule for degree 3 and 4


def quadrature(dim, degree):
    """UFL measure metadata for hypershape's rule of `degree` on the `dim`-simplex."""
    rule = MINSYM.get((dim, degree))
    if rule is None:
        if dim > 1:
            print(f"warning: no copy of PETSc's MINSYM rule for dim {dim} degree {degree}; "
                  "using Basix's default rule of that degree")
        return {"quadrature_degree": degree}
    # tuples, not arrays: UFL puts the metadata into the form's signature with str()
    return {"quadrature_degree": degree, "quadrature_rule": "custom",
            "quadrature_points": tuple(tuple(p) for p, _ in rule),
            "quadrature_weights": tuple(w for _, w in rule)}


class Diverged(Exception):
    pass


class DolfinxScene:
    """The scene's discretisation in DOLFINx on hypershape's mesh."""

    def __init__(self, scene, hs, factor="lu", rtol=1e-9, atol=1e-12, max_it=20):
        import numpy as np
        import ufl
        from dolfinx import fem, mesh
        from dolfinx.fem.petsc import NonlinearProblem
        from dolfinx.nls.petsc import NewtonSolver
        from mpi4py import MPI
        from petsc4py import PETSc

        eff = scene["effects"]
        nh, dp, gt = eff["neo_hookean"], eff["dirichlet_patch"], eff["gaussian_traction"]
        unknown = set(eff) - {"neo_hookean", "dirichlet_patch", "gaussian_traction"}
        if unknown:
            sys.exit(f"bench_dolfinx: effects {sorted(unknown)} are not reproduced here")
        E, nu = float(nh["E"]), float(nh["nu"])
        mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
        self.rtol, self.atol = rtol, atol
        nodes, cells, nv, deg = hs["nodes"], hs["cells"], hs["n_vertices"], hs["degree"]
        dim = nodes.shape[1]
        self.dim, self.degree = dim, deg
        cell = "triangle" if dim == 2 else "tetrahedron"
        domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.Cell(cell, geometric_dimension=dim), 1))
        msh = mesh.create_mesh(MPI.COMM_WORLD, cells[:, : dim + 1].copy(), nodes[:nv].copy(), domain)
        self.msh = msh
        V = fem.VectorFunctionSpace(msh, ("Lagrange", deg))
        self.V = V
        tdim, fdim = msh.topology.dim, msh.topology.dim - 1

        # Clamp: boundary facets whose vertices all lie within r (+ hypershape's 1e-9 max(1, r)).
        c, r = np.array(dp["center"], float), float(dp["radius"])
        tol = 1e-9 * max(1.0, r)
        clamped = mesh.locate_entities_boundary(
            msh, fdim, lambda X: np.sqrt(((X[:dim].T - c) ** 2).sum(axis=1)) <= r + tol)
        msh.topology.create_connectivity(fdim, tdim)
        boundary = mesh.exterior_facet_indices(msh.topology)
        neumann = np.setdiff1d(boundary, clamped)
        tags = mesh.meshtags(msh, fdim, np.concatenate([clamped, neumann]).astype(np.int32),
                             np.concatenate([np.full(len(clamped), 2), np.full(len(neumann), 1)]).astype(np.int32))
        order = np.argsort(tags.indices)
        tags = mesh.meshtags(msh, fdim, tags.indices[order], tags.values[order])
        zero = np.zeros(dim, dtype=PETSc.ScalarType)
        dofs = fem.locate_dofs_topological(V, fdim, clamped)
        self.bc = fem.dirichletbc(zero, dofs, V)
        self.n_clamped_nodes = len(dofs)

        qdeg, fqdeg = 2 * deg - 1, 2 * deg + 2  # hypershape's SpaceOptions defaults
        dx = ufl.Measure("dx", domain=msh, metadata=quadrature(dim, qdeg))
        ds = ufl.Measure("ds", domain=msh, subdomain_data=tags, metadata=quadrature(dim - 1, fqdeg))
        x = ufl.SpatialCoordinate(msh)
        self.p_n = fem.Constant(msh, np.array(gt["center"], dtype=PETSc.ScalarType))
        g = np.array(gt["direction"], float)
        self.g = fem.Constant(msh, (g / np.linalg.norm(g)).astype(PETSc.ScalarType))
        gamma = float(gt["gamma"])
        phi = ufl.exp(-ufl.dot(x - self.p_n, x - self.p_n) / (2 * gamma ** 2))
        self.phi_form = fem.form(phi * ds(1))
        self.inv_norm = fem.Constant(msh, PETSc.ScalarType(1.0))  # 1 / I_N
        self.alpha = fem.Constant(msh, PETSc.ScalarType(0.0))

        self.u = fem.Function(V)
        v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
        F = ufl.variable(ufl.Identity(dim) + ufl.grad(self.u))
        J = ufl.det(F)
        # The seed's energy (appendix A): W = mu/2 (tr F^T F - d - 2 ln J) + lambda/2 (ln J)^2,
        # with d = dim: in 2D plane strain F_33 = 1 adds tr 1 - 1 = 0.
        W = mu / 2 * (ufl.tr(F.T * F) - dim - 2 * ufl.ln(J)) + lam / 2 * ufl.ln(J) ** 2
        t_unit = self.g * phi * self.inv_norm
        energy = W * dx - self.alpha * ufl.dot(t_unit, self.u) * ds(1)
        residual = ufl.derivative(energy, self.u, v)
        jacobian = ufl.derivative(residual, self.u, du)
        self.f_ext_form = fem.form(ufl.dot(t_unit, v) * ds(1))
        self.f_ext = fem.petsc.create_vector(self.f_ext_form)

        bc = self.bc
        owner = self
        self.newton_iterations = 0

        class GuardedProblem(NonlinearProblem):
            """Stops Newton on a residual that is not finite (an inverted element: ln J), and
            counts the Jacobian assemblies (= Newton iterations = numeric factorisations)."""

            def F(self, x, b):
                super().F(x, b)
                if not np.isfinite(b.norm()):
                    raise Diverged("residual not finite (det F <= 0)")

            def J(self, x, A):
                owner.newton_iterations += 1
                super().J(x, A)

        problem = GuardedProblem(residual, self.u, bcs=[bc], J=jacobian)
        newton = NewtonSolver(MPI.COMM_WORLD, problem)
        newton.convergence_criterion = "residual"
        newton.rtol = 0.0  # the test is absolute, set per alpha: ||R|| <= rtol ||alpha f_ext|| + atol
        newton.max_it = max_it
        newton.error_on_nonconvergence = False
        newton.report = False
        self.newton = newton
        self._set_factor(newton.krylov_solver, factor)

        # K(0), the same for every load case of the mesh (dead loads): factorised once here.
        self.u.x.array[:] = 0.0
        K0 = fem.petsc.assemble_matrix(fem.form(jacobian), bcs=[bc])
        K0.assemble()
        self.K0 = K0
        self.ksp0 = PETSc.KSP().create(MPI.COMM_WORLD)
        self.ksp0.setOperators(K0)
        self._set_factor(self.ksp0, factor)
        self.a0 = self.f_ext.duplicate()
        self.backup = self.u.vector.duplicate()

        self.n_free = V.dofmap.index_map.size_global * V.dofmap.index_map_bs - dim * self.n_clamped_nodes
        self.newton_solves = 0
        self.failed = 0

    @staticmethod
    def _set_factor(ksp, factor):
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType(factor)
        pc.setFactorSolverType("mumps")

    def set_load_point(self, p_n, g):
        """Moves the traction (per load case in a factory): I_N and f_ext are recomputed."""
        import numpy as np
        from dolfinx import fem
        from petsc4py import PETSc
        self.p_n.value[:] = p_n
        self.g.value[:] = np.asarray(g, float) / np.linalg.norm(g)
        self.inv_norm.value = 1.0
        I_N = fem.assemble_scalar(self.phi_form)
        self.inv_norm.value = 1.0 / I_N
        with self.f_ext.localForm() as loc:
            loc.set(0.0)
        fem.petsc.assemble_vector(self.f_ext, self.f_ext_form)
        self.f_ext.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fem.petsc.set_bc(self.f_ext, [self.bc], scale=0.0)
        self.f_ext_norm = self.f_ext.norm()
        return I_N

    def max_u(self, vec=None):
        import numpy as np
        arr = self.u.x.array if vec is None else vec.array
        n_owned = self.V.dofmap.index_map.size_local
        return float(np.sqrt((arr.reshape(-1, self.dim)[:n_owned] ** 2).sum(axis=1)).max())

    def newton_at(self, alpha):
        """One Newton solve at alpha from the current state; True if converged."""
        self.alpha.value = alpha
        self.newton.atol = self.rtol * abs(alpha) * self.f_ext_norm + self.atol
        try:
            _, ok = self.newton.solve(self.u)
        except (Diverged, RuntimeError):
            ok = False
        self.newton_solves += 1
        return ok

    def solve_to(self, alpha_from, alpha_to, max_failures=12):
        """Load continuation from the current (converged) state at alpha_from to alpha_to: the
        full step first; a failed step is undone and halved, a success doubles the next."""
        a, step = alpha_from, alpha_to - alpha_from
        self.u.vector.copy(self.backup)
        failures = 0
        while a != alpha_to:
            a_try = alpha_to if abs(step) >= abs(alpha_to - a) else a + step
            if self.newton_at(a_try):
                a = a_try
                self.u.vector.copy(self.backup)
                step *= 2
            else:
                self.backup.copy(self.u.vector)
                self.u.x.scatter_forward()
                step /= 2
                failures += 1
                self.failed += 1
                if failures > max_failures:
                    return False
        return True

    def reset(self):
        self.u.x.array[:] = 0.0

    def solve_for_target(self, target, target_rtol=1e-3, max_solves=30):
        """The paper's way: proportional guess from the linear response, then a secant search
        on alpha, each alpha solved from the last converged state. From rest."""
        self.reset()
        self.newton_iterations = self.newton_solves = self.failed = 0
        self.ksp0.solve(self.f_ext, self.a0)
        alpha = target / self.max_u(self.a0)
        pts = [(0.0, 0.0)]
        a_state = 0.0
        for _ in range(max_solves):
            if not self.solve_to(a_state, alpha):
                return {"converged": False, "alpha": alpha, "max_displacement": self.max_u()}
            a_state = alpha
            m = self.max_u()
            pts.append((alpha, m))
            if abs(m / target - 1) <= target_rtol:
                return {"converged": True, "alpha": alpha, "max_displacement": m}
            (a0, m0), (a1, m1) = pts[-2], pts[-1]
            alpha = a1 + (target - m1) * (a1 - a0) / (m1 - m0)
        return {"converged": False, "alpha": alpha, "max_displacement": self.max_u()}

    def node_values(self, nodes):
        """u at hypershape's nodes (matched by coordinates), n_nodes x dim; NaN if unmatched."""
        import numpy as np
        xs = self.V.tabulate_dof_coordinates()[:, : self.dim]
        vals = self.u.x.array.reshape(-1, self.dim)[: len(xs)]
        key = lambda p: tuple(np.round(p, 9))  # noqa: E731
        where = {key(p): i for i, p in enumerate(xs)}
        out = np.full(nodes.shape, np.nan)
        for i, p in enumerate(nodes):
            j = where.get(key(p))
            if j is not None:
                out[i] = vals[j]
        return out


# ----------------------------------------------------------------------------------------------


def median(v):
    return statistics.median(v) if v else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", nargs="?", default=str(ROOT / "configs/scenes/disk_p2.yaml"),
                    help="scene YAML (default: configs/scenes/disk_p2.yaml, the seed's disk)")
    ap.add_argument("--case", action="append", metavar="DEGREE:H",
                    help="element degree and mesh.h (repeatable; default 1:0.04 and 2:0.08)")
    ap.add_argument("--targets", default="0.3,0.1,0.5,0.2,0.4",
                    help="target max|u| of the load cases, solved in turn (default 0.3,0.1,0.5,0.2,0.4: "
                    "not sorted, as the factory's stratified targets come; hypershape's first increment "
                    "is the previous load case's, so the order matters to it)")
    ap.add_argument("--repeat", type=int, default=3,
                    help="timed passes over the targets, after one warm-up pass (default 3)")
    ap.add_argument("--rounds", type=int, default=2,
                    help="times the two sides take turns per case (default 2)")
    ap.add_argument("--hypershape", default=str(ROOT / "build/hypershape"), help="the binary to measure")
    ap.add_argument("--hypershape-args", default="", metavar="ARGS",
                    help="extra arguments for hypershape solve, e.g. PETSc options "
                    "('-pc_factor_mat_solver_type mumps')")
    ap.add_argument("--factor", choices=["lu", "cholesky"], default="lu",
                    help="DOLFINx's factorisation (MUMPS; default lu)")
    ap.add_argument("--json", default=str(ROOT / "results/bench_dolfinx.json"))
    ap.add_argument("--workdir", default=None, help="where the scenes and hypershape outputs go "
                    "(default: results/bench_dolfinx/)")
    args = ap.parse_args()
    import_dolfinx()
    import logging
    logging.getLogger().setLevel(logging.WARNING)  # FFCx's JIT compiler logs every build at INFO
    import numpy as np
    import yaml
    import dolfinx

    exe = Path(args.hypershape).resolve()
    if not os.access(exe, os.X_OK):
        sys.exit(f"bench_dolfinx: {exe} is not an executable (build first: scripts/setup.sh)")
    scene = yaml.safe_load(Path(args.scene).read_text())
    targets = [float(t) for t in args.targets.split(",")]
    hs_extra = shlex.split(args.hypershape_args)
    multi = supports_targets(exe)
    if not multi:
        print(f"warning: {exe} has no `solve --targets/--repeat`: one process per load case, timed by "
              "its `solve` phase (cold: symbolic factorisation and K(0) included; no first increment "
              "carried over from the previous load case)", flush=True)
    cases = args.case or ["1:0.04", "2:0.08"]
    workdir = Path(args.workdir) if args.workdir else ROOT / "results/bench_dolfinx"
    workdir.mkdir(parents=True, exist_ok=True)
    solver_block = scene.get("solver") or {}
    rtol = float(solver_block.get("rtol", 1e-9))
    target_rtol = float(solver_block.get("target_rtol", 1e-3))
    n_targets, passes = len(targets), args.repeat + 1
    report = {"scene": in_repo(Path(args.scene)), "hypershape": in_repo(exe), "hypershape_args": hs_extra,
              "hypershape_timing": "per load case inside one process (solve --targets --repeat)" if multi
              else "one process per load case, its 'solve' phase (cold)",
              "targets": targets, "repeat": args.repeat,
              "rounds": args.rounds, "load_average_start": os.getloadavg(),
              "dolfinx_version": dolfinx.__version__, "dolfinx_factor": f"mumps {args.factor}",
              "machine": f"{os.cpu_count()} cores (shared), 1 process per side, OMP/BLAS threads 1",
              "cases": []}

    for spec in cases:
        deg_s, h_s = spec.split(":")
        degree, h = int(deg_s), float(h_s)
        name = f"{Path(args.scene).stem}_p{degree}_h{h:g}"
        print(f"\n=== {name}: P{degree}, h {h:g}, targets {targets}, {args.repeat} timed passes", flush=True)
        hs = hypershape_side(exe, scene, degree, h, targets, passes, workdir, name, hs_extra, multi)

        t0 = time.perf_counter()
        dx = DolfinxScene(scene, hs, factor=args.factor, rtol=rtol)
        g = scene["effects"]["gaussian_traction"]
        I_N = dx.set_load_point(g["center"], g["direction"])
        setup_s = time.perf_counter() - t0
        n_hs = len(hs["nodes"])
        print(f"DOLFINx set-up (mesh, space, forms incl. JIT, K(0) factorisation): {setup_s:.2f} s; "
              f"{dx.n_free} free unknowns, {dx.n_clamped_nodes} clamped nodes, I_N {I_N:.6g}")

        # 1. Agreement at the same alpha: DOLFINx at hypershape's alpha (untimed).
        agree = []
        for k, T in enumerate(targets):
            a_hs, m_hs = float(hs["alpha"][k]), float(hs["max_displacement"][k])
            dx.reset()
            ok = dx.solve_to(0.0, a_hs)
            m_dx = dx.max_u()
            agree.append({"target": T, "alpha": a_hs, "max_u_hypershape": m_hs, "max_u_dolfinx": m_dx,
                          "converged": ok, "rel_diff": m_dx / m_hs - 1})
        # the last solve left u at the last target's alpha: compare the nodal field.
        u_dx = dx.node_values(hs["nodes"])
        matched = ~np.isnan(u_dx[:, 0])
        field_diff = float(np.abs(u_dx[matched] - hs["u_last"][matched]).max() /
                           np.sqrt((hs["u_last"] ** 2).sum(axis=1)).max())
        clamped_hs = int((np.abs(hs["u_last"]).sum(axis=1) == 0).sum())
        print("same alpha, max|u| DOLFINx / hypershape - 1: " +
              ", ".join(f"{a['rel_diff']:+.1e}" for a in agree) +
              f"; nodal u (last target): max |du| / max|u| {field_diff:.1e} over {matched.sum()}/{n_hs} "
              f"matched nodes; nodes with u = 0: hypershape {clamped_hs}, DOLFINx clamped {dx.n_clamped_nodes}")

        # 2. Timed: the same targets, the same passes (first = warm-up), secant search from rest;
        # the two sides take turns `rounds` times (hypershape's first round is the run above),
        # so that a shift in the host's load falls on both.
        warm_hs, warm_dx, dx_runs, hs_runs = [], [], [], []
        nodes0 = hs["nodes"]
        for rnd in range(args.rounds):
            if rnd > 0:
                hs = hypershape_side(exe, scene, degree, h, targets, passes, workdir, name, hs_extra, multi)
                if hs["nodes"].shape != nodes0.shape or not np.array_equal(hs["nodes"], nodes0):
                    sys.exit("bench_dolfinx: hypershape meshed the scene differently in another run")
            runs = load_cases(hs)
            hs_runs += runs
            warm_hs += runs[n_targets:]
            runs = []
            for p in range(passes):
                for T in targets:
                    t0 = time.perf_counter()
                    r = dx.solve_for_target(T, target_rtol=target_rtol)
                    r["seconds"] = time.perf_counter() - t0
                    r.update(target=T, newton_iterations=dx.newton_iterations, solves=dx.newton_solves,
                             failed_increments=dx.failed)
                    runs.append(r)
            dx_runs += runs
            warm_dx += runs[n_targets:]
        alpha_diff = [d["alpha"] / s["alpha"] - 1 for d, s in zip(warm_dx, warm_hs)]
        umax_diff = [d["max_displacement"] / s["max_displacement"] - 1 for d, s in zip(warm_dx, warm_hs)]
        med_hs = median([r["seconds"] for r in warm_hs])
        med_dx = median([r["seconds"] for r in warm_dx])
        case = {
            "name": name, "degree": degree, "h": h, "vertices": hs["n_vertices"],
            "cells": int(len(hs["cells"])), "nodes": n_hs, "unknowns": dx.n_free,
            "hypershape_s_median": med_hs, "dolfinx_s_median": med_dx, "ratio": med_dx / med_hs,
            "hypershape_newton_median": median([r["newton_iterations"] for r in warm_hs]),
            "dolfinx_newton_median": median([r["newton_iterations"] for r in warm_dx]),
            "dolfinx_solves_median": median([r["solves"] for r in warm_dx]),
            "hypershape_ms_per_newton": 1e3 * sum(r["seconds"] for r in warm_hs) /
            max(1, sum(r["newton_iterations"] for r in warm_hs)),
            "dolfinx_ms_per_newton": 1e3 * sum(r["seconds"] for r in warm_dx) /
            max(1, sum(r["newton_iterations"] for r in warm_dx)),
            "converged": {"hypershape": sum(r["converged"] for r in warm_hs),
                          "dolfinx": sum(r["converged"] for r in warm_dx), "of": len(warm_hs)},
            "alpha_rel_diff_max": float(np.max(np.abs(alpha_diff))),
            "max_u_rel_diff_max": float(np.max(np.abs(umax_diff))),
            "same_alpha": {"max_u_rel_diff_max": float(max(abs(a["rel_diff"]) for a in agree)),
                           "field_rel_diff": field_diff, "per_target": agree},
            "dolfinx_setup_s": setup_s,
            "hypershape_runs": hs_runs, "dolfinx_runs": dx_runs,
        }
        report["cases"].append(case)
        print(f"hypershape {med_hs:.3f} s/load case (median Newton its {case['hypershape_newton_median']:g}), "
              f"DOLFINx {med_dx:.3f} s/load case (median Newton its {case['dolfinx_newton_median']:g}, "
              f"solves {case['dolfinx_solves_median']:g}) -> {case['ratio']:.1f}x; "
              f"alpha |rel diff| <= {case['alpha_rel_diff_max']:.1e}", flush=True)

    rows = ["| case | unknowns | hypershape s/load case | DOLFINx s/load case | ratio | Newton its (hs / DOLFINx) "
            "| ms per Newton it. (hs / DOLFINx) | converged (hs / DOLFINx) "
            "| alpha rel. diff (max) | max\\|u\\| rel. diff at the same alpha |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    for c in report["cases"]:
        rows.append(f"| {Path(args.scene).stem} P{c['degree']} h {c['h']:g} | {c['unknowns']} | "
                    f"{c['hypershape_s_median']:.3f} | {c['dolfinx_s_median']:.3f} | {c['ratio']:.1f}x | "
                    f"{c['hypershape_newton_median']:g} / {c['dolfinx_newton_median']:g} | "
                    f"{c['hypershape_ms_per_newton']:.0f} / {c['dolfinx_ms_per_newton']:.0f} | "
                    f"{c['converged']['hypershape']}/{c['converged']['dolfinx']} of {c['converged']['of']} | "
                    f"{c['alpha_rel_diff_max']:.1e} | {c['same_alpha']['max_u_rel_diff_max']:.1e} |")
    table = "\n".join(rows)
    report["table"] = table
    report["load_average_end"] = os.getloadavg()
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(report, indent=1))
    print(f"\nmedians over {args.rounds} x {args.repeat} x {n_targets} warm load cases (targets {targets}), "
          f"1 process each, {report['machine']}:\n{table}\n-> {args.json}")


if __name__ == "__main__":
    main()
