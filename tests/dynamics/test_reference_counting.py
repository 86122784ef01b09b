"""The kernels compiled without Numba's reference counting (``_nrt=False``: the right-hand side and the explicit
step's loop, docs/performance.md) are safe to share with code compiled with it.

A Numba function called from compiled code inherits the caller's ``_nrt`` setting unless it sets its own, and a
dispatcher compiles each signature once: a kernel first compiled inside a caller without reference counting is
the one every later caller gets. Such a kernel that *returns* an array hands it back without the reference the
caller owns; a caller with reference counting then releases it once too often, and the heap is corrupted
(measured before this test: the case-1 right-hand side compiled, then the nonlinear kernels called from a
counting function, ``malloc(): unaligned tcache chunk detected``, the process aborted). So no kernel of the
package returns an array, or anything holding one, through a call: the nonlinear elements' kernels write into
their arguments, ``delay.view`` and the stiff part's overload (:func:`~drillstring.dynamics.rom.stiff_part`) are
inlined into their compiled callers. ``benchmarks/reference_counting_scan.py`` lists, after a cold compilation of
every kind of run, the compiled kernels that return arrays (none but those inlined). The two tests below repeat
the two corruptions measured, each in a fresh process with glibc's heap checks (``MALLOC_CHECK_=3``); both
aborted before the change. Each process compiles into a cache folder of its own (``NUMBA_CACHE_DIR`` in the test's
temporary folder): the kernels are compiled in the order the test sets, not loaded from a cache another order
wrote (Numba's cache key does not hold the flags a kernel's callees were compiled with: drillstring.kernel_cache,
"What the key does not hold"), and no other process of the suite writes that folder while this one reads it
(this test, run beside the suite's other workers on a cold shared cache, once died of SIGSEGV in CI).
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap


def _run_checked(script: str, cache) -> subprocess.CompletedProcess:
    env = dict(os.environ, MALLOC_CHECK_="3", NUMBA_CACHE_DIR=str(cache))
    return subprocess.run([sys.executable, "-c", textwrap.dedent(script)], capture_output=True, text=True,
                          env=env, timeout=600)


def test_nonlinear_kernels_after_the_case_1_right_hand_side_keep_the_heap_intact(tmp_path):
    """Case 1's right-hand side compiled (its nonlinear kernels inside a caller without reference counting),
    then those kernels called many times from a function with reference counting."""
    run = _run_checked("""
        import numpy as np
        from numba import njit
        from drillstring.api import simulate
        from drillstring.case import load_case
        from drillstring.fem.mesh import build_mesh
        from drillstring.fem.sections import hollow_circle
        from drillstring.forces.nonlinear import (_kinetic_forces_kernel, _mass_coupling_kernel,
                                                  _project_coupling_kernel, _strain_energy_forces_kernel,
                                                  nonlinear_elements)

        case = load_case("reference")
        case = case.model_copy(update={"model": case.model.model_copy(update={"nonlinear": "full"}),
                                       "simulation": case.simulation.model_copy(update={"t_end": 0.05})})
        simulate(case)

        @njit
        def drive(n_calls, q, qd, a, phi_e, f, fk, coupling, out, work):
            for _ in range(n_calls):
                _strain_energy_forces_kernel(q, a[0], a[2], a[3], a[5], f)
                _kinetic_forces_kernel(q, qd, a[1], a[2], a[4], a[6], fk, coupling)
                _mass_coupling_kernel(q, a[1], a[2], a[4], a[6], coupling)
                _project_coupling_kernel(coupling, phi_e, out, work)

        section = hollow_circle(0.127, 0.095, 210e9, 7850.0, 0.29)
        mesh = build_mesh([30.0, 12.0], [section, section], 10.0)
        nl = nonlinear_elements(mesh)
        rng = np.random.default_rng(1)
        q, qd = 1e-3 * rng.standard_normal(mesh.n_dofs), 1e-3 * rng.standard_normal(mesh.n_dofs)
        n = 5
        phi_e = rng.standard_normal((mesh.n_elements, 12, n))
        arrays = (nl.inv_length, nl.xi, nl.weights, nl.slope, nl.rotation, nl.axial_stiffness, nl.polar_inertia)
        buffers = (np.empty(mesh.n_dofs), np.empty(mesh.n_dofs), np.empty((mesh.n_elements, 2, 4)),
                   np.empty((n, n)), np.empty((2, n)))
        for _ in range(200):
            drive(50, q, qd, arrays, phi_e, *buffers)
        print("heap intact")
    """, tmp_path / "numba")
    assert run.returncode == 0 and "heap intact" in run.stdout, run.stderr[-2000:]


def test_the_stiff_part_after_the_implicit_explicit_loop_keeps_the_models_arrays(tmp_path):
    """The implicit-explicit loop (no reference counting) compiles the stiff part first; then the exponential
    step's linearisation (a function with reference counting) calls it many times on the same model: the model's
    ω² stays as it was and the heap intact (before: ``malloc(): unaligned tcache chunk detected``)."""
    run = _run_checked("""
        import gc
        import numpy as np
        from drillstring.api import simulate
        from drillstring.case import load_case
        from drillstring.dynamics.reduced.build import case_reduced_model
        from drillstring.dynamics.steps.exponential import bit_law_linearisation

        case = load_case("aarsnes2019")
        case = case.model_copy(update={"simulation": case.simulation.model_copy(update={"t_end": 0.05,
                                                                                         "method": "ark43"})})
        simulate(case)
        model = case_reduced_model(case)
        data = model.case2_data
        y = np.zeros(model.initial_state(0.0, 0).shape[0])
        before = data.omega2.copy()
        for _ in range(20000):
            bit_law_linearisation(data, 0.0, y)
        gc.collect()
        junk = [np.random.rand(100) for _ in range(20000)]
        print("intact" if np.array_equal(before, data.omega2) else "changed")
    """, tmp_path / "numba")
    assert run.returncode == 0 and "intact" in run.stdout, run.stderr[-2000:]
