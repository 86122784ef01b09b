"""Survey for the stiff integrator (issue 24): along short runs of the built-in cases, the largest eigenvalues of
the right-hand side's Jacobian (central differences of the compiled right-hand side, modal rows), the family of
the stiffest one's eigenvector, the rank of the nonlinear part J − J_linear, and the mean accepted DOPRI5 step
against the explicit stability limit 3.3/|λ|. Run:

    .venv/bin/python benchmarks/stiff_part_survey.py [reference stick_slip contact aarsnes2019]
"""
import sys

import numpy as np
from drillstring.case import load_case
from drillstring.dynamics.rom import case_reduced_model
from drillstring.dynamics.runge_kutta import integrate
from drillstring.dynamics.simulate import simulate_model

RUNS = {"reference": (None, 10.0), "stick_slip": (None, 20.0), "contact": (None, 5.0), "aarsnes2019": ("ramp", 14.0)}

def jac(model, t, y, history=None):
    n2 = 2 * model.size
    J = np.empty((n2, n2))
    for j in range(n2):
        step = 1e-7 * max(1.0, abs(y[j]))
        p, m = y.copy(), y.copy(); p[j] += step; m[j] -= step
        J[:, j] = (model.rhs(t, p, history)[:n2] - model.rhs(t, m, history)[:n2]) / (2 * step)
    return J

def main(names):
    for name in names:
        start, t_end = RUNS[name]
        case = load_case(name)
        if start:
            case = case.model_copy(update={"initial": case.initial.model_copy(update={"start": start})})
        model = case_reduced_model(case)
        n = model.size
        y0 = model.initial_state(case.initial.lateral_perturbation, case.initial.seed)
        res = simulate_model(model, t_end=t_end, output_step=0.01)
        st = res.stats
        print(f"== {name}: n = {n} modes ({', '.join(f'{f}: {list(model.family).count(f)}' for f in sorted(set(model.family)))}),"
              f" {t_end} s: {st['n_accepted']} accepted, {st['n_rejected']} rejected, {st['n_rhs']} RHS, "
              f"mean step {t_end / st['n_accepted']:.3g} s, solver {st['wall_time']:.2f} s", flush=True)
        times = np.linspace(0.0, t_end, 8)
        history = model.start_history(y0)  # the run's bit history, recorded along it (read at its end below)
        sol = integrate(lambda t, y: model.rhs(t, y, history), (0.0, t_end), y0, t_out=times,
                        observe=lambda t, y: y, rtol=1e-6, atol=1e-9, max_steps=5_000_000,
                        on_dense_step=(lambda *step: model.record_history(history, *step))
                        if model.bit_rock.delayed else None)
        fam = np.asarray(model.family)
        lin = np.zeros((2 * n, 2 * n)); lin[:n, n:] = np.eye(n); lin[n:, :n] = -np.diag(model.omega2); lin[n:, n:] = -model.damping
        for t, y in zip(sol.t, sol.y):
            J = jac(model, t, y, history)
            w, v = np.linalg.eig(J)
            order = np.argsort(-np.abs(w))
            top = w[order[0]]
            vec = np.abs(v[:n, order[0]]) ** 2 + np.abs(v[n:, order[0]]) ** 2
            shares = {f: vec[fam == f].sum() / vec.sum() for f in sorted(set(fam))}
            main_f = max(shares, key=shares.get)
            nl = J - lin
            sv = np.linalg.svd(nl, compute_uv=False)
            rank = int((sv > 1e-3 * sv[0]).sum()) if sv[0] > 0 else 0
            obs = model.observe(t, y, history)
            print(f"  t = {t:6.2f} s: |λ| top 3 = {', '.join(f'{abs(w[i]):.3g}' for i in order[:3])} 1/s "
                  f"(top λ = {top.real:.3g}{top.imag:+.3g}i, {main_f} {shares[main_f]:.0%}); "
                  f"max |ω| {np.abs(model.angular_frequencies).max():.3g}; nonlinear part rank {rank} "
                  f"(σ1 {sv[0]:.3g}); 3.3/|λ| = {3.3 / abs(top):.3g} s; bit speed {obs[1]:.2f} rad/s", flush=True)

if __name__ == "__main__":
    main(sys.argv[1:] or list(RUNS))
