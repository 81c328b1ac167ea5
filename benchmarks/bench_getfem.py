"""vemwear against GetFEM 5.4 on triangles and tetrahedra, where the method is P1 FEM.

On triangles the lowest-order virtual element space is the P1 finite element space
and the projection is exact (docs/method.md §2), so vemwear and a P1 code that makes
the same contact choices compute the same numbers up to round-off. This script solves
the paper's Example 5.2, data set 1, on vemwear's ``triangles`` mesh of (0, 2) x (0, 1)
(every grid rectangle cut from lower left to upper right) with both codes:
clamped at x = 0, contact at y = 0, traction-free top and right, lam = eta = 4,
f1 = (0, -0.06), p(r) = 0.4 r_+, g = 0.1, mu = 0.2, kappa = 2, v* = (1, 0), T = 1, and
``--steps`` uniform time steps at every size (64 by default: the paper's k = 1/64,
65 levels t_0 ... t_64; the same grid at every size, so the cost per level is compared).
Each child first solves the same problem on 4 x 2 rectangles with 2 steps, so that
the first-call set-up of its libraries (MUMPS, MKL, SciPy) is not counted as compute.

``--3d``: the 3D example of ``benchmarks/bench_3d.py`` on vemwear's ``tetrahedra`` mesh
of (0, 2) x (0, 1) x (0, 1) (every grid hexahedron cut into six, Kuhn), size n meaning
n x n/2 x n/2 hexahedra (8 16 24 by default): clamped at x = 0, contact at z = 0,
traction-free elsewhere, f1 = (0, 0, -0.06), v* = (1, 0, 0), the data above. The
lowest-order space on tetrahedra is P1 too, and vemwear weighs a contact node by its
share of the contact faces' areas (``P1Space3D.trace_weights``: |F| / 3 at each vertex
of a triangle), which is the vertex rule of GetFEM's ``IM_NC(3,1)`` on the faces of the
tetrahedra. The GetFEM child is the same with ``Mesh('ptND')``, ``FEM_PK(3,1)``,
``IM_TETRAHEDRON(2)`` and the normal -e_z; the friction direction nstar = -v*/|v*| is
tangent to the contact plane. The warm-up is 4 x 2 x 2.

* **GetFEM** (a child process with an interpreter that can ``import getfem``: this one,
  else Debian's ``/usr/bin/python3`` with ``python3-getfem``; if neither, the script
  says so and exits 0). The parent exports vemwear's mesh (points and triangles) to an
  ``.npz`` file, the child builds ``Mesh('pt2D')`` from it, P1 Lagrange ``FEM_PK(2,1)``
  displacement, ``add_isotropic_linearized_elasticity_brick`` with Lamé lambda = lam and
  mu = eta (sigma = 2 eta eps + lam tr(eps) I), the body force by a source term, the
  clamping by ``add_Dirichlet_condition_with_simplification``. The contact terms are
  integrated on y = 0 with the faces of ``IM_NC(2,1)`` (the trapezoidal rule: vemwear's
  nodal quadrature, weights half the adjacent edge lengths):
  ``0.4 pos_part(u.Normal - w) (Test_u.Normal + mu nstar.(Test_u - (Test_u.Normal) Normal))``
  with nstar = -v*/|v*| (normal compliance and Coulomb friction), and the rigid layer
  u.Normal <= g by a P1 multiplier on the contact boundary in the augmented-Lagrangian
  form ``lam Test_u.Normal - (lam - pos_part(lam + r (u.Normal - g))) Test_lam / r``
  (r = lam + 2 eta; nodal complementarity, like vemwear's). Every level is one
  ``md.solve`` (GetFEM's Newton, max_res 1e-10, at most 50 iterations, full steps,
  linear solver ``--lsolver``: MUMPS by default, its sparse direct solver; Debian's
  build links the sequential MUMPS). Between levels the wear
  w^{n+1} = w^n + k kappa |v*| p(u_nu^n - w^n) is updated at the nodes in NumPy and
  passed back as data.
* **vemwear** (a child process of this interpreter): ``rectangle_triangles`` +
  ``tag_rectangle`` (3D: ``box_tetrahedra`` + ``tag_box``) + ``Problem`` + ``simulate(problem, SolverOptions("newton",
  backend=--backend))``, storing u at every level (GetFEM has it at every level too).

Both children solve all levels t_0 ... t_N. **Compute** time is measured inside each
child from building the mesh to the wear at T (mesh building included on both sides:
``Mesh('pt2D')`` from the arrays and its regions for GetFEM, the generator and the
tagging for vemwear); interpreter start, imports (vemwear's child first imports the
modules a session with vemwear has loaded: SciPy's sparse solvers and spatial tools,
matplotlib's paths) and reading the mesh file are excluded. **Whole** is the wall
time of the child process seen from here. The sizes run interleaved ``--repeat``
times; the table gives min / median / max, the ratio of the medians
(GetFEM / vemwear), the Newton iterations of all levels, and the agreement of the
wear at T: the relative difference of the maximal wear and the largest nodal
difference over the maximal wear (largest over the repeats). **Floor** is measured in
vemwear's child right after its timed run, on the same problem: the assembly of K, the
factorization with the Schur block on the contact dofs and one block solve with a
column per level (the linear algebra the run cannot do without); the table gives its
median and vemwear's median compute time over it. A second table splits vemwear's
compute time by phase (from ``result.timings``): before the time loop (mesh, problem,
assembly, result arrays), the factorization with the Schur block, and the levels with
the recovery of u. A third gives the CPU time of the compute (``time.process_time``
in each child: all its threads), which waiting for a busy machine's cores does not
inflate; with one thread on each side its ratio is the comparison of the work done.

Threads: neither side is told anything by default (GetFEM's build has no OpenMP;
MUMPS calls OpenBLAS, vemwear's default backend is PARDISO with MKL's threads where
installed, on one thread below 20,000 unknowns: ``SCHUR_SERIAL_MAX``). ``--threads N``
sets OMP/OPENBLAS/MKL_NUM_THREADS=N in both children.
SciPy's SuperLU (``--backend scipy``) is vemwear's single-threaded direct solver.
GetFEM's own SuperLU (``--lsolver superlu``) crashes (SIGSEGV) in Debian's 5.4.2 build,
even on plain linear elasticity, so MUMPS is its only direct solver there.

Usage::

    python benchmarks/bench_getfem.py                              # 32x16 ... 256x128
    python benchmarks/bench_getfem.py --sizes 32 64 --repeat 5 --steps 16
    python benchmarks/bench_getfem.py --threads 1 --backend scipy  # one thread each
    python benchmarks/bench_getfem.py --3d --sizes 8 16 24         # tetrahedra

``--json FILE`` also writes the table's numbers (times, iterations, agreement) per size.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

# Problem data (Example 5.2, data set 1, and its 3D analogue of benchmarks/bench_3d.py,
# by the dimension); the GetFEM child receives them in its .npz.
LAM, ETA = 4.0, 4.0
F1 = {2: (0.0, -0.06), 3: (0.0, 0.0, -0.06)}
C_P, G, MU, KAPPA = 0.4, 0.1, 0.2, 2.0
V_STAR = {2: (1.0, 0.0), 3: (1.0, 0.0, 0.0)}
T_END = 1.0
SIDES = {"clamped": "xmin", "contact": "zmin", "traction": ["xmax", "ymin", "ymax", "zmax"]}

_GETFEM_CHILD = r"""
import json, sys, time
import numpy as np
import getfem as gf

gf.util_trace_level(0)
gf.util_warning_level(0)
mesh_file, out_file, lsolver = sys.argv[1], sys.argv[2], sys.argv[3]
d = np.load(mesh_file)
P = np.ascontiguousarray(d["points"].T)
TRI = np.ascontiguousarray(d["cells"].T.astype(np.int32))
dim = P.shape[0]  # triangles in 2D, tetrahedra in 3D
steps, T_end = int(d["steps"]), float(d["T"])
lam, eta, cp, g, mu, kappa = (float(d[k]) for k in ("lam", "eta", "cp", "g", "mu", "kappa"))
f1, v_star = d["f1"], d["v_star"]
CONTACT, CLAMPED = 1, 2

def solve(P, TRI, steps):
    t0, c0 = time.perf_counter(), time.process_time()
    m = gf.Mesh("pt2D", P, TRI) if dim == 2 else gf.Mesh("ptND", P, TRI)
    if m.nbpts() != P.shape[1] or np.abs(m.pts() - P).max() > 0:
        raise SystemExit("GetFEM renumbered the mesh points")
    down, left = -np.eye(dim)[dim - 1], -np.eye(dim)[0]
    m.set_region(CONTACT, m.outer_faces_with_direction(down, 0.01))
    m.set_region(CLAMPED, m.outer_faces_with_direction(left, 0.01))
    mfu = gf.MeshFem(m, dim)
    mfu.set_fem(gf.Fem(f"FEM_PK({dim},1)"))
    mfs = gf.MeshFem(m, 1)
    mfs.set_fem(gf.Fem(f"FEM_PK({dim},1)"))
    mim = gf.MeshIm(m, gf.Integ("IM_TRIANGLE(2)" if dim == 2 else "IM_TETRAHEDRON(2)"))
    # faces: the vertex rule (trapezoidal on edges, |F|/3 at each vertex of a triangle),
    # vemwear's nodal quadrature
    mim_c = gf.MeshIm(m, gf.Integ(f"IM_NC({dim},1)"))

    md = gf.Model("real")
    md.add_fem_variable("u", mfu)
    md.add_filtered_fem_variable("lam", mfs, CONTACT)
    md.add_initialized_data("lame_lambda", [lam])
    md.add_initialized_data("lame_mu", [eta])
    md.add_isotropic_linearized_elasticity_brick(mim, "u", "lame_lambda", "lame_mu")
    md.add_initialized_data("f1", f1)
    md.add_source_term_brick(mim, "u", "f1")
    md.add_Dirichlet_condition_with_simplification("u", CLAMPED)
    w = np.zeros(mfs.nbdof())
    md.add_initialized_fem_data("w", mfs, w)
    md.add_initialized_data("cp", [cp])
    md.add_initialized_data("g", [g])
    md.add_initialized_data("muf", [mu])
    md.add_initialized_data("nstar", -v_star / np.linalg.norm(v_star))
    md.add_initialized_data("r", [lam + 2.0 * eta])
    md.add_nonlinear_term(
        mim_c,
        "cp*pos_part(u.Normal - w)*(Test_u.Normal"
        " + muf*(nstar.(Test_u - (Test_u.Normal)*Normal)))",
        CONTACT,
    )
    md.add_nonlinear_term(
        mim_c,
        "lam*(Test_u.Normal) - (1/r)*(lam - pos_part(lam + r*(u.Normal - g)))*Test_lam",
        CONTACT,
    )
    # the contact nodes: scalar dofs of w and the normal (last) dofs of u at the same points
    cd = mfs.basic_dof_on_region(CONTACT)
    ud = mfu.basic_dof_on_region(CONTACT)
    un = mfu.basic_dof_nodes()
    uy = ud[dim - 1 :: dim]
    if np.abs(un[:, ud[0::dim]] - un[:, uy]).max() > 0:
        raise SystemExit("unexpected dof layout of the vector P1 space")
    xs = mfs.basic_dof_nodes()[:, cd]
    o1, o2 = np.lexsort(xs[::-1]), np.lexsort(un[:, uy][::-1])
    if np.abs(xs[:, o1] - un[:, uy][:, o2]).max() > 0:
        raise SystemExit("scalar and vector contact dofs do not match")
    cd, uy = cd[o1], uy[o2]
    alpha = kappa * float(np.linalg.norm(v_star))
    k = T_end / steps
    iters = 0
    for n in range(steps + 1):
        nit, conv = md.solve(
            "max_res", 1e-10, "max_iter", 50, "lsolver", lsolver, "lsearch", "simplest"
        )
        if not conv:
            raise SystemExit(f"GetFEM's Newton did not converge at level {n}")
        iters += int(nit)
        if n < steps:
            u_nu = -md.variable("u")[uy]  # outward normal -e_dim
            w[cd] += k * alpha * cp * np.maximum(u_nu - w[cd], 0.0)
            md.set_variable("w", w)
    cpu = time.process_time() - c0
    return time.perf_counter() - t0, cpu, iters, xs[:, o1].T, w[cd], int(mfu.nbdof())


# a small run first: first-call set-up of the libraries is not compute time
solve(np.ascontiguousarray(d["warm_points"].T),
      np.ascontiguousarray(d["warm_cells"].T.astype(np.int32)), 2)
compute, cpu, iters, x_out, w_out, ndof = solve(P, TRI, steps)
np.savez(out_file, x=x_out, w=w_out)
print(json.dumps({"compute": compute, "cpu": cpu, "iterations": iters, "dofs": ndof}))
"""

_VEMWEAR_CHILD = r"""
import importlib, json, sys, time
import numpy as np
from vemwear.contact import LinearCompliance
from vemwear.mesh import rectangle_triangles, tag_rectangle
from vemwear.mesh.generate3d import box_tetrahedra, tag_box
from vemwear.simulate import Problem, SolverOptions, TimeGrid, simulate
from vemwear.solvers.backends import resolve_backend, schur_factorize
from vemwear.vem import Material

# a warm process: modules that vemwear or a session around it imports (SciPy's sparse
# solvers and spatial tools, matplotlib) are loaded before the timed runs; without
# matplotlib.path and multiprocessing the first 32 x 16 run is about 6 ms slower
for name in ("matplotlib.path", "multiprocessing", "scipy.sparse.csgraph",
             "scipy.sparse.linalg", "scipy.spatial", "threadpoolctl",
             "vemwear.solvers.backends.pardiso"):
    try:
        importlib.import_module(name)
    except ImportError:
        pass
a = json.loads(sys.argv[1])


def solve(divisions, steps):
    t0, c0 = time.perf_counter(), time.process_time()
    if len(divisions) == 2:
        mesh = tag_rectangle(rectangle_triangles((2.0, 1.0), divisions))
    else:  # clamped at x = 0, contact at z = 0, traction-free elsewhere
        mesh = tag_box(box_tetrahedra((2.0, 1.0, 1.0), divisions), a["sides"])
    pr = Problem(
        mesh, Material(a["lam"], a["eta"]), TimeGrid.uniform(a["T"], steps),
        f1=tuple(a["f1"]), p=LinearCompliance(a["cp"]), g=a["g"], mu=a["mu"],
        kappa=a["kappa"], v_star=tuple(a["v_star"]),
    )
    r = simulate(pr, SolverOptions("newton", backend=a["backend"]))
    return time.perf_counter() - t0, time.process_time() - c0, pr, r


# the run's linear algebra alone, on its matrix: assembly of K, factorization with the
# Schur block on the contact dofs, and one block solve of a column per level
def floor(pr, levels):
    t0 = time.perf_counter()
    pr.space.stiffness(pr.material, pr.stabilization)
    s = pr.discrete.system
    f = schur_factorize(s.K, s.contact_dofs.ravel(), s.dof_points, a["backend"])
    f.solve(np.ones((s.n_free, levels), order="F"))
    return time.perf_counter() - t0


solve(a["warm"], 2)  # first-call set-up of the libraries is not compute time
compute, cpu, pr, r = solve(a["divisions"], a["steps"])
mesh = pr.mesh
np.savez(a["out"], x=r.contact_points, w=r.wear[-1])
# where the compute time goes: before the time loop (mesh, problem, assembly, result
# arrays), the factorization with its Schur block, the levels with the recovery of u
tm = r.timings
phases = {"before": compute - tm["total"], "setup": tm["setup"], "loop": tm["time_loop"]}
print(json.dumps({"compute": compute, "cpu": cpu, "floor": floor(pr, len(r.t)), "phases": phases,
                  "iterations": int(r.iterations.sum()),
                  "dofs": mesh.points.size, "levels": len(r.t),
                  "backend": resolve_backend(a["backend"])}))
"""


def getfem_python(explicit: str | None = None) -> str | None:
    """An interpreter that can ``import getfem`` (and numpy), or None."""
    cands = [explicit] if explicit else [sys.executable, "/usr/bin/python3"]
    for exe in dict.fromkeys(cands):
        if not exe or not os.path.exists(exe):
            continue
        proc = subprocess.run([exe, "-c", "import getfem, numpy"], capture_output=True)
        if proc.returncode == 0:
            return exe
    return None


def _getfem_version() -> str:
    try:
        proc = subprocess.run(
            ["dpkg-query", "-W", "-f=${Version}", "python3-getfem"],
            capture_output=True,
            text=True,
        )
    except OSError:
        return "unknown version"
    return f"python3-getfem {proc.stdout.strip()}" if proc.returncode == 0 else "unknown version"


def divisions(n: int, dim: int) -> tuple[int, ...]:
    """The grid of size ``n``: n x n/2 rectangles (2D), n x n/2 x n/2 hexahedra (3D)."""
    return (n, n // 2) if dim == 2 else (n, n // 2, n // 2)


def _simplices(divs: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """vemwear's triangles (2D) or tetrahedra (3D) mesh: points and vertex lists."""
    from vemwear.mesh import rectangle_triangles
    from vemwear.mesh.generate3d import box_tetrahedra

    if len(divs) == 2:
        mesh = rectangle_triangles((2.0, 1.0), divs)
        offsets, cells = mesh.cell_offsets, mesh.cell_vertices
    else:
        mesh3 = box_tetrahedra((2.0, 1.0, 1.0), divs)
        mesh, offsets, cells = mesh3, mesh3.cell_vertex_offsets, mesh3.cell_vertex_ids
    d = len(divs)
    if not np.all(np.diff(offsets) == d + 1):
        raise SystemExit("the mesh generator gave a cell that is not a simplex")
    return mesh.points, cells.reshape(-1, d + 1)


def _mesh_file(n: int, dim: int, steps: int, path: str) -> None:
    """Export vemwear's mesh and the data for the GetFEM child."""
    points, cells = _simplices(divisions(n, dim))
    warm_points, warm_cells = _simplices(divisions(4, dim))
    np.savez(
        path,
        points=points,
        cells=cells,
        warm_points=warm_points,
        warm_cells=warm_cells,
        steps=steps,
        T=T_END,
        lam=LAM,
        eta=ETA,
        cp=C_P,
        g=G,
        mu=MU,
        kappa=KAPPA,
        f1=np.array(F1[dim]),
        v_star=np.array(V_STAR[dim]),
    )


def _run(cmd: list[str], env: dict[str, str]) -> tuple[dict, float]:
    t = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t
    if proc.returncode != 0:
        tail = (proc.stderr.strip() or proc.stdout.strip())[-600:]
        raise SystemExit(f"{cmd[0]} {cmd[1]} failed (exit {proc.returncode}): {tail}")
    lines = [s for s in proc.stdout.splitlines() if s.startswith("{")]
    return json.loads(lines[-1]), wall


def _agreement(vem_npz: str, gf_npz: str) -> tuple[float, float, float]:
    """(max wear of vemwear, relative difference of max wear, max nodal diff / max wear).

    vemwear's contact nodes (the clamped ones are not contact nodes) are found among
    GetFEM's by their coordinates, which both codes take from the same mesh file."""
    a, b = np.load(vem_npz), np.load(gf_npz)
    at = {tuple(x): i for i, x in enumerate(np.round(b["x"], 12).tolist())}
    near = np.array([at.get(tuple(x), -1) for x in np.round(a["x"], 12).tolist()])
    if len(near) == 0 or (near < 0).any():
        raise SystemExit("the contact nodes of the two codes differ")
    wb = b["w"]
    wmax = float(np.abs(a["w"]).max())
    rel_max = abs(float(wb.max()) - float(a["w"].max())) / wmax
    rel_nodal = float(np.abs(wb[near] - a["w"]).max()) / wmax
    return wmax, rel_max, rel_nodal


def _stats(v: list[float]) -> str:
    return f"{min(v):7.3f} {statistics.median(v):7.3f} {max(v):7.3f}"


def _spec(n: int, dim: int, steps: int, backend: str, out: str) -> dict:
    """The vemwear child's problem, as the GetFEM child reads it from the mesh file."""
    return {
        "divisions": divisions(n, dim),
        "warm": divisions(4, dim),
        "sides": SIDES,
        "steps": steps,
        "T": T_END,
        "lam": LAM,
        "eta": ETA,
        "f1": F1[dim],
        "cp": C_P,
        "g": G,
        "mu": MU,
        "kappa": KAPPA,
        "v_star": V_STAR[dim],
        "backend": backend,
        "out": out,
    }


def _label(n: int, dim: int) -> str:
    return "x".join(str(k) for k in divisions(n, dim))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        default=None,
        help="divisions in x (y, and z in 3D, get half): 32 -> 32x16; "
        "default 32 64 128 256 (2D), 8 16 24 (3D)",
    )
    ap.add_argument("--3d", dest="dim3", action="store_true", help="tetrahedra of the box")
    ap.add_argument("--steps", type=int, default=64, help="uniform time steps at every size")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--backend", default="auto", help="vemwear's backend: auto, scipy, pardiso")
    ap.add_argument(
        "--lsolver",
        default="mumps",
        help="GetFEM's linear solver (mumps; superlu crashed in Debian's 5.4.2 build)",
    )
    ap.add_argument("--threads", type=int, default=None, help="OMP/OPENBLAS/MKL threads")
    ap.add_argument("--getfem-python", default=None, help="interpreter that imports getfem")
    ap.add_argument("--json", default=None, help="also write the table's numbers to this file")
    args = ap.parse_args(argv)
    dim = 3 if args.dim3 else 2
    sizes = args.sizes or ([8, 16, 24] if dim == 3 else [32, 64, 128, 256])

    py = getfem_python(args.getfem_python)
    if py is None:
        tried = args.getfem_python or f"{sys.executable} and /usr/bin/python3"
        print(f"GetFEM is not importable (tried {tried}): nothing to compare.")
        print("Debian: apt-get install python3-getfem")
        return 0
    env = dict(os.environ)
    if args.threads is not None:
        for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
            env[var] = str(args.threads)
    threads = "not set" if args.threads is None else str(args.threads)
    print(
        f"machine: {os.cpu_count()} cores; vemwear python {sys.version.split()[0]}, "
        f"backend {args.backend}; GetFEM ({_getfem_version()}) via {py}, "
        f"lsolver {args.lsolver}; threads {threads}"
    )
    what = "Example 5.2 set 1 on triangles" if dim == 2 else "the 3D example on tetrahedra"
    print(f"{what}, {args.steps} steps ({args.steps + 1} levels), interleaved x {args.repeat}")
    cols = ("gf", "vem", "gf_whole", "vem_whole", "floor", "gf_cpu", "vem_cpu")
    with tempfile.TemporaryDirectory() as tmp:
        child = os.path.join(tmp, "getfem_child.py")
        with open(child, "w") as fh:
            fh.write(_GETFEM_CHILD)
        times = {n: {c: [] for c in cols} for n in sizes}
        phases: dict[int, dict[str, list[float]]] = {n: {} for n in sizes}
        info: dict[int, dict] = {n: {"rel_max": 0.0, "rel_nodal": 0.0} for n in sizes}
        for n in sizes:
            _mesh_file(n, dim, args.steps, os.path.join(tmp, f"mesh{n}.npz"))
        for _ in range(args.repeat):
            for n in sizes:  # interleaved
                mesh = os.path.join(tmp, f"mesh{n}.npz")
                gf_out, vem_out = os.path.join(tmp, f"gf{n}.npz"), os.path.join(tmp, f"vem{n}.npz")
                g, g_wall = _run([py, child, mesh, gf_out, args.lsolver], env)
                spec = _spec(n, dim, args.steps, args.backend, vem_out)
                v, v_wall = _run([sys.executable, "-c", _VEMWEAR_CHILD, json.dumps(spec)], env)
                for c, val in zip(
                    cols,
                    (g["compute"], v["compute"], g_wall, v_wall, v["floor"], g["cpu"], v["cpu"]),
                    strict=True,
                ):
                    times[n][c].append(val)
                for k, val in v["phases"].items():
                    phases[n].setdefault(k, []).append(val)
                wmax, rel_max, rel_nodal = _agreement(vem_out, gf_out)
                if g["dofs"] != v["dofs"]:
                    raise SystemExit(f"dofs differ: GetFEM {g['dofs']}, vemwear {v['dofs']}")
                it = info[n]
                it.update(dofs=v["dofs"], levels=v["levels"], wmax=wmax, backend=v["backend"])
                it.update(its=f"{g['iterations']}/{v['iterations']}")
                it["rel_max"] = max(it["rel_max"], rel_max)
                it["rel_nodal"] = max(it["rel_nodal"], rel_nodal)
    print(
        "seconds: min med max; ratio = GetFEM median / vemwear median; floor: vemwear's "
        "median over the median of its floor"
    )
    head = (
        f"{'size':>8} {'dofs':>7} {'lev':>4} | {'GetFEM compute':>23} | {'vemwear compute':>23} |"
        f" {'ratio':>6} | {'floor':>7} {'x':>5} | {'GetFEM whole':>23} | {'vemwear whole':>23} | {'ratio':>6} |"
        f" {'Newton G/V':>10} | {'max wear':>9} {'dmax':>8} {'dnodal':>8}"
    )
    print(head)
    print("-" * len(head))
    for n in sizes:
        t, it = times[n], info[n]
        ratio = statistics.median(t["gf"]) / statistics.median(t["vem"])
        ratio_w = statistics.median(t["gf_whole"]) / statistics.median(t["vem_whole"])
        it.update(ratio=ratio, gf=t["gf"], vem=t["vem"])
        print(
            f"{_label(n, dim):>8} {it['dofs']:>7} {it['levels']:>4} | {_stats(t['gf']):>23} |"
            f" {_stats(t['vem']):>23} | {ratio:6.1f} | {statistics.median(t['floor']):7.4f}"
            f" {statistics.median(t['vem']) / statistics.median(t['floor']):5.2f} |"
            f" {_stats(t['gf_whole']):>23} |"
            f" {_stats(t['vem_whole']):>23} | {ratio_w:6.1f} | {it['its']:>10} |"
            f" {it['wmax']:9.6f} {it['rel_max']:8.1e} {it['rel_nodal']:8.1e}"
        )
    print(
        f"dofs: {dim} x vertices (clamped included); Newton G/V: iterations of all levels; "
        "dmax = |max w_G - max w_V| / max w_V, dnodal = max |w_G - w_V| / max w_V at T "
        "(largest over the repeats)"
    )
    print(
        "vemwear's compute by phase, ms (medians): before the time loop (mesh, problem, "
        "assembly, result arrays), the factorization with the Schur block "
        "(result.timings['setup']), the levels with the recovery of u (['time_loop'])"
    )
    for n in sizes:
        ph = {k: 1e3 * statistics.median(v) for k, v in phases[n].items()}
        print(
            f"{_label(n, dim):>8}  before {ph['before']:8.2f}  set-up {ph['setup']:8.2f}"
            f"  levels {ph['loop']:8.2f}  of {1e3 * statistics.median(times[n]['vem']):8.2f}"
        )
    print(
        "CPU time of the compute (all threads of each child; on a loaded machine the wall "
        "time waits for the cores, the CPU time does not), seconds: min med max"
    )
    for n in sizes:
        t = times[n]
        ratio_cpu = statistics.median(t["gf_cpu"]) / statistics.median(t["vem_cpu"])
        info[n].update(ratio_cpu=ratio_cpu, gf_cpu=t["gf_cpu"], vem_cpu=t["vem_cpu"])
        print(
            f"{_label(n, dim):>8}  GetFEM {_stats(t['gf_cpu'])}  vemwear {_stats(t['vem_cpu'])}"
            f"  ratio {ratio_cpu:6.1f}"
        )
    used = sorted({info[n]["backend"] for n in sizes})
    print(f"vemwear's backend: {', '.join(used)}; GetFEM's linear solver: {args.lsolver}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({_label(n, dim): info[n] for n in sizes}, fh, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
