"""The SE+ ensemble of random reduced matrices (Soize 2000, 2005) and the random reduced model built on it."""

import math

import numpy as np
import pytest

from drillstring.dynamics.rom import case_reduced_model
from drillstring.stochastic.random_matrices import (
    ModelDispersion,
    dispersion_limit,
    germ,
    measured_dispersion,
    model_generator,
    random_matrix,
    random_reduced_model,
)

N_DRAWS = 4000


@pytest.mark.parametrize("n, delta", [(3, 0.3), (8, 0.5)])
def test_germ_mean_is_identity_within_its_known_standard_error(n, delta):
    """E{G} = I: each entry of the mean of N draws lies within 5 standard errors of I, the standard error
    from the known variance Var(G_jk) = δ²(1 + δ_jk)/(n + 1) (a wrong diagonal scale of H, e.g. without σ,
    moves the mean by O(1), hundreds of standard errors)."""
    rng = np.random.default_rng(1)
    draws = np.array([germ(n, delta, rng) for _ in range(N_DRAWS)])
    error = draws.mean(axis=0) - np.eye(n)
    standard = np.sqrt(delta**2 * (1.0 + np.eye(n)) / (n + 1) / N_DRAWS)
    assert np.max(np.abs(error) / standard) < 5.0
    # the entries' variance itself, within 10 % (N = 4000: the sampling error of a variance is ~3-5 %)
    variance = draws.var(axis=0)
    np.testing.assert_allclose(variance, delta**2 * (1.0 + np.eye(n)) / (n + 1), rtol=0.15)


@pytest.mark.parametrize("n, delta", [(3, 0.3), (8, 0.5), (20, 0.1)])
def test_measured_dispersion_equals_delta(n, delta):
    """δ̂ = (mean ‖G − I‖²_F / n)^{1/2} of 4000 draws equals δ within 3 % (the standard error of δ̂² here is
    below 1.5 % of δ², so 3 % on δ is over 4 standard errors)."""
    rng = np.random.default_rng(2)
    draws = np.array([germ(n, delta, rng) for _ in range(N_DRAWS)])
    assert measured_dispersion(draws) == pytest.approx(delta, rel=0.03)


def test_every_draw_is_positive_definite_even_near_the_limit():
    """2000 draws at δ = 0.95 δ_max: every G and every L G Lᵀ positive definite (smallest eigenvalue > 0)."""
    rng = np.random.default_rng(3)
    n = 6
    delta = 0.95 * dispersion_limit(n)
    nominal = np.diag(np.arange(1.0, n + 1.0) ** 2)
    for _ in range(2000):
        assert np.linalg.eigvalsh(germ(n, delta, rng))[0] > 0.0
        drawn = random_matrix(nominal, delta, rng)
        assert np.linalg.eigvalsh(drawn)[0] > 0.0


def test_random_matrix_mean_is_the_nominal_matrix():
    """E{L G Lᵀ} = A for a full positive-definite A, and a semi-definite A (a zero eigenvalue) keeps its null
    space exactly in every draw."""
    rng = np.random.default_rng(4)
    a = np.array([[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]])
    delta = 0.4
    draws = np.array([random_matrix(a, delta, rng) for _ in range(N_DRAWS)])
    # Var(Ã_jk) <= ‖L‖⁴ δ²·2/(n+1) bounds each entry's standard error
    bound = np.linalg.norm(a, 2) * delta * math.sqrt(2.0 / 4.0 / N_DRAWS)
    assert np.max(np.abs(draws.mean(axis=0) - a)) < 5.0 * bound
    singular = np.diag([0.0, 2.0, 5.0])
    drawn = random_matrix(singular, delta, rng)
    assert np.all(drawn[0] == 0.0) and np.all(drawn[:, 0] == 0.0)
    assert np.linalg.eigvalsh(drawn[1:, 1:])[0] > 0.0


def test_zero_dispersion_draws_nothing():
    rng = np.random.default_rng(5)
    state = rng.bit_generator.state
    a = np.diag([1.0, 2.0])
    assert random_matrix(a, 0.0, rng) is a
    np.testing.assert_array_equal(germ(4, 0.0, rng), np.eye(4))
    assert rng.bit_generator.state == state


def test_dispersion_out_of_range_is_refused_with_field_value_and_range():
    with pytest.raises(ValueError, match=r"uncertainty\.model\.stiffness_dispersion = -0\.1: must be"):
        ModelDispersion(stiffness=-0.1)
    with pytest.raises(ValueError, match=r"uncertainty\.model\.mass_dispersion = 1\.2"):
        ModelDispersion.from_mapping({"mass_dispersion": 1.2})
    with pytest.raises(ValueError, match=r"uncertainty\.model\.damping: unknown key"):
        ModelDispersion.from_mapping({"damping": 0.1})
    # a family of n = 2 modes: δ_max = sqrt(3/7) = 0.6547
    with pytest.raises(ValueError, match=r"damping_dispersion = 0\.7: must be in \[0, 0\.6547\).*n = 2 modes"):
        ModelDispersion(damping=0.7).check({"torsional": 2})
    with pytest.raises(ValueError, match=r"dispersion = 0\.9: must be in \[0, 0\.6547\)"):
        germ(2, 0.9, np.random.default_rng(0))


@pytest.fixture(scope="module")
def small_model(small_case):
    return case_reduced_model(small_case)


def test_zero_dispersions_give_the_nominal_model_itself(small_model):
    assert random_reduced_model(small_model, ModelDispersion(), model_generator(0, 3)) is small_model


def test_realized_model_solves_the_random_generalized_eigenproblem(small_model):
    """The realized model is a ROM of the same form: per family, Φ̃ = Φ X, ω̃² = λ, D̃' = Xᵀ D̃ X with
    Xᵀ M̃ X = I and K̃ X = M̃ X Λ; hence the realized linear frequencies are the square roots of the
    generalized eigenvalues of (K̃, M̃) redrawn from the same stream, the rigid axial mode stays rigid (ω = 0)
    and the damping stays block diagonal and positive semi-definite."""
    dispersion = ModelDispersion(mass=0.2, stiffness=0.3, damping=0.4)
    a = random_reduced_model(small_model, dispersion, model_generator(7, 1))
    b = random_reduced_model(small_model, dispersion, model_generator(7, 1))
    np.testing.assert_array_equal(a.basis, b.basis)  # redrawn from (seed, index)
    assert a.family == small_model.family and a.basis.shape == small_model.basis.shape
    rigid = small_model.family.index("rigid_axial")
    assert a.omega2[rigid] == 0.0
    assert not np.allclose(a.omega2, small_model.omega2)
    np.testing.assert_array_equal(a.damping[small_model.damping == 0.0], 0.0)
    assert np.linalg.eigvalsh(0.5 * (a.damping + a.damping.T))[0] > -1e-9 * np.abs(a.damping).max()
    # the same draws by hand, family by family, in the order of random_reduced_model
    from scipy import linalg

    from drillstring.stochastic.random_matrices import family_columns

    rng = model_generator(7, 1)
    for columns in family_columns(small_model).values():
        if not len(columns):
            continue
        m = random_matrix(np.eye(len(columns)), 0.2, rng)
        k = random_matrix(np.diag(small_model.omega2[columns]), 0.3, rng)
        random_matrix(small_model.damping[np.ix_(columns, columns)], 0.4, rng)
        expected = linalg.eigh(k, m, eigvals_only=True)
        np.testing.assert_allclose(a.omega2[columns], expected, rtol=1e-10, atol=1e-9 * expected.max())
        # Φ̃ᵀ M_phys Φ̃ = Xᵀ X and the mass-normalisation Xᵀ M̃ X = I
        x = np.linalg.lstsq(small_model.basis[:, columns], a.basis[:, columns], rcond=None)[0]
        np.testing.assert_allclose(x.T @ m @ x, np.eye(len(columns)), atol=1e-8)


def test_study_realizations_draw_their_own_model_and_zero_dispersion_is_bit_identical(small_case, tmp_path):
    """In a Monte Carlo study: δ = 0 gives the same realizations, bit for bit, as a study without model
    uncertainty; δ > 0 changes every realization but not the nominal run nor the drawn parameters, and the
    store records the dispersions with the seed (enough to redraw)."""
    import zarr

    from drillstring.stochastic import execution
    from drillstring.stochastic import montecarlo as mc

    def settings(model):
        return mc.StudySettings(laws=(mc.weight_on_hook_normal(small_case, 5000.0),), samples=2, seed=5,
                                t_end=0.3, output_step=0.05, model_dispersion=model)

    plain, zero, model = settings((0.0, 0.0, 0.0)), settings((0.0, 0.0, 0.0)), settings((0.1, 0.2, 0.3))
    assert plain == zero
    runs = {}
    for name, s in {"plain": plain, "model": model}.items():
        mc.check_study(small_case, s)
        mc.run_study(small_case, s, tmp_path / f"{name}.zarr", execution.Engine(workers=1))
        runs[name] = zarr.open_group(str(tmp_path / f"{name}.zarr"), mode="r")
    bare = mc.run_realization(small_case, plain, 1)
    again = mc.run_realization(small_case, zero, 1)
    for key in bare.observables:
        np.testing.assert_array_equal(bare.observables[key], again.observables[key])
    a, b = runs["plain"], runs["model"]
    np.testing.assert_array_equal(a["weight_on_hook"][:], b["weight_on_hook"][:])
    np.testing.assert_array_equal(a["nominal_bit_speed"][:], b["nominal_bit_speed"][:])
    for i in range(2):
        assert not np.array_equal(a["bit_speed"][i], b["bit_speed"][i])
    assert list(b.attrs["settings"]["model_dispersion"]) == [0.1, 0.2, 0.3] and b.attrs["settings"]["seed"] == 5
    from drillstring.stochastic.analysis import load_study, study_statistics

    stats = study_statistics(load_study(tmp_path / "model.zarr"))
    assert list(stats.attrs["model_dispersion"]) == [0.1, 0.2, 0.3] and stats.attrs["seed"] == 5
    assert list(study_statistics(load_study(tmp_path / "plain.zarr")).attrs["model_dispersion"]) == [0.0] * 3


def test_a_dispersion_above_the_family_limit_is_refused_before_running(small_case):
    """small_case has 2 elastic axial modes (and the rigid one, without stiffness) and 2 torsional modes: the
    stiffness germs are of size 2, δ_max = sqrt(3/7) = 0.655; the axial family is named first."""
    from drillstring.stochastic import montecarlo as mc

    s = mc.StudySettings(laws=(mc.weight_on_hook_normal(small_case, 5000.0),), samples=2, t_end=0.3,
                         output_step=0.05, model_dispersion=(0.0, 0.7, 0.0))
    with pytest.raises(ValueError,
                       match=r"stiffness_dispersion = 0\.7: must be in \[0, 0\.6547\).*axial family of n = 2"):
        mc.check_study(small_case, s)
    with pytest.raises(ValueError, match=r"uncertainty\.model\.damping_dispersion = -0\.5"):
        mc.StudySettings(laws=(mc.weight_on_hook_normal(small_case, 5000.0),), samples=2,
                         model_dispersion=(0.0, 0.0, -0.5))


def test_the_case_files_uncertainty_model_table_reaches_the_study_settings(small_case):
    """[uncertainty.model] alone (no parameter law) declares the model uncertainty; the study then draws the
    default weight-on-hook law beside it; an argument overrides the table; a value >= 1 is refused by the
    case with the field."""
    from drillstring.api import study_settings
    import tomllib

    from drillstring.case import CaseError, case_from_dict

    toml = small_case.to_toml() + "\n[uncertainty.model]\nstiffness_dispersion = 0.2\ndamping_dispersion = 0.3\n"
    case = case_from_dict(tomllib.loads(toml))
    settings, bare = study_settings(case, samples=2, t_end=0.3, output_step=0.05)
    assert settings.model_dispersion == (0.0, 0.2, 0.3) and bare.uncertainty is None
    assert [path for path, _ in settings.laws] == ["weight_on_hook"]
    settings, _ = study_settings(case, model={"mass_dispersion": 0.1}, samples=2, t_end=0.3, output_step=0.05)
    assert settings.model_dispersion == (0.1, 0.0, 0.0)
    with pytest.raises(CaseError, match="stiffness_dispersion"):
        case_from_dict(tomllib.loads(toml.replace("stiffness_dispersion = 0.2", "stiffness_dispersion = 1.2")))


def test_probabilistic_map_realizations_draw_random_matrices_per_sample(torsional_case):
    """A probabilistic map's realization (point, sample) runs the model of model_generator(seed, sample): its
    stability outputs equal those of that realized model, differ from the nominal one, and δ = 0 leaves the
    realization bit-identical to a map without model uncertainty."""
    from drillstring.dynamics.rom import case_reduced_model
    from drillstring.stochastic import probabilistic_map as pm
    from drillstring.stochastic.operating_map import MapSettings
    from drillstring.stochastic.runs import stability_outputs

    grid = MapSettings((10.0,), (6e4, 7e4), t_end=0.3, output_step=0.05)
    plain = pm.SampledMapSettings(grid, samples=2, seed=4, sigma=1.0)
    model = pm.SampledMapSettings(grid, samples=2, seed=4, sigma=1.0, model_dispersion=(0.1, 0.2, 0.3))
    pm.check_sampled_map(torsional_case, model)
    index = 1 * 2 + 1  # point 1, sample 1
    a, b = pm.run_realization(torsional_case, plain, index), pm.run_realization(torsional_case, model, index)
    assert a.status == b.status == 1
    realized_case = pm.point_uncertainty(torsional_case, model, 1).apply(
        pm.point_case(torsional_case, model, 1), b.values["input_values"])
    realized = random_reduced_model(case_reduced_model(realized_case), model.model, model_generator(4, 1))
    expected, _ = stability_outputs(realized)
    assert b.values["torsional_growth_rate"] == pytest.approx(expected["torsional_growth_rate"], rel=1e-9)
    assert b.values["torsional_growth_rate"] != a.values["torsional_growth_rate"]
    zero = pm.SampledMapSettings(grid, samples=2, seed=4, sigma=1.0, model_dispersion=(0.0, 0.0, 0.0))
    c = pm.run_realization(torsional_case, zero, index)
    assert all(c.values[k] == a.values[k] or (np.isnan(c.values[k]) and np.isnan(a.values[k]))
               for k in a.values if k != "input_values")


def test_sensitivity_refuses_a_case_with_model_uncertainty_rather_than_ignore_it(small_case, tmp_path):
    from drillstring.api import sensitivity
    from drillstring.case import ModelUncertaintyTable, UncertaintyTable

    table = UncertaintyTable(parameters={"operation.top_speed": "uniform 90 110 rpm"},
                             model=ModelUncertaintyTable(stiffness_dispersion=0.1))
    case = small_case.model_copy(update={"uncertainty": table})
    with pytest.raises(ValueError, match=r"^\[uncertainty\.model\] of the case: Sobol' sensitivity runs do not"):
        sensitivity(case, samples=8, out=tmp_path / "s")
    assert not (tmp_path / "s").exists()


def test_rigid_modes_stay_rigid_and_first_with_a_top_drive():
    """With a top drive the torsional family starts with the rigid rotation (ω = 0): in every realized model it
    is still the family's first column, with ω = 0 exactly and the nominal rigid shape (scaled by the random
    mass), and so is the rigid axial translation."""
    from drillstring.case import load_case

    case = load_case("stick_slip")
    case = case.model_copy(update={
        "mesh": case.mesh.model_copy(update={"max_element_length": 50.0}),
        "reduced_model": case.reduced_model.model_copy(update={
            "axial_modes": 2, "torsional_modes": 3, "lateral_modes": 2, "lateral_cutoff": 0.0})})
    nominal = case_reduced_model(case)
    rotation, translation = nominal.rigid_rotation_column, nominal.family.index("rigid_axial")
    assert rotation is not None and nominal.omega2[rotation] == 0.0
    for index in range(5):
        realized = random_reduced_model(nominal, ModelDispersion(0.3, 0.3, 0.3), model_generator(2, index))
        assert realized.rigid_rotation_column == rotation
        for column in (rotation, translation):
            assert realized.omega2[column] == 0.0
            shape, drawn = nominal.basis[:, column], realized.basis[:, column]
            scale = (drawn @ shape) / (shape @ shape)
            np.testing.assert_allclose(drawn, scale * shape, atol=1e-12 * np.abs(drawn).max())


def test_the_limit_is_that_of_each_germ_the_rigid_mode_left_out_of_the_stiffness(small_model):
    """small_case's axial family: the rigid mode and 2 elastic ones. Its mass germ has n = 3 (δ_max = 0.7071),
    its stiffness germ n = 2 (δ_max = 0.6547, the rigid mode has no stiffness): δ_K = 0.68 is refused before
    any draw, δ_M = 0.68 is not."""
    with pytest.raises(ValueError, match=r"stiffness_dispersion = 0\.68: must be in \[0, 0\.6547\).*axial"):
        random_reduced_model(small_model, ModelDispersion(stiffness=0.68), model_generator(0, 0))
    ModelDispersion(mass=0.68).check({"axial": (3, 2, 3)})
