"""The recognition's forecast of a touch (planner.planning.forecast)."""

from __future__ import annotations

import contextlib
import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.codec import plan_to_dict
from planner.planning import plan as plan_module
from planner.planning.budget import UNIT_US, Budget
from planner.planning.config import StrategyConfig
from planner.planning.forecast import forecast_distinguishing, update_size, with_forecast
from planner.planning.plan import plan_session
from planner.planning.predicted import observed, predictions
from planner.recognition.session import Session
from planner.types import SensingPath, SensorBounds
from tests.conftest import WORKSPACE, analysed, object_set, touched_session

BOUNDS = [SensorBounds(0.0, 0.0), SensorBounds(1.0, math.radians(3))]
SENSOR = (WORKSPACE.radius, 0.0)


def touched(name: str, bounds: SensorBounds, seed: int, touches: int) -> Session:
    return touched_session(name, bounds, seed, touches)[1]


@pytest.mark.parametrize("name", ["thesis_like", "symmetric"])
@pytest.mark.parametrize("bounds", BOUNDS, ids=["exact", "1mm-3deg"])
@settings(max_examples=6, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), touches=st.integers(2, 3))
def test_a_path_sure_to_distinguish_is_forecast_so(name, bounds, seed, touches):
    # where the outcome model tells every class apart for sure, so does the recognition
    session = touched(name, bounds, seed, touches)
    classes = {h.equivalence_class for h in session.hypotheses}
    if session.status != "ambiguous" or len(classes) > 24:
        return
    found = analysed(session)
    c = found.candidates
    before = session.hypotheses
    for i in np.argsort(-found.info.p_distinguishing, kind="stable")[:3]:
        path = SensingPath(tuple(c.origins[i]), tuple(c.directions[i]), float(c.lengths[i]))
        value = forecast_distinguishing(session, path)
        assert 0.0 <= value <= 1.0
        if found.info.p_distinguishing[i] >= 1 - 1e-9:
            assert value == pytest.approx(1.0)
    assert session.hypotheses == before  # the session itself is untouched


def test_plan_session_forecasts_the_first_paths_within_the_budget():
    session = touched("thesis_like", BOUNDS[1], 3, 2)
    assert session.status == "ambiguous"
    two = plan_session(
        session, SENSOR, StrategyConfig(budget_ms=None, budget_work=None, forecast=2), 0
    )
    assert len(two.paths) > 2
    assert all(p.p_forecast is not None for p in two.paths[:2])
    assert all(p.p_forecast is None for p in two.paths[2:])
    assert plan_to_dict(two, 1)["paths"][0]["p_forecast"] == two.paths[0].p_forecast
    none = plan_session(
        session, SENSOR, StrategyConfig(budget_ms=None, budget_work=None, forecast=0), 0
    )
    assert all(p.p_forecast is None for p in none.paths)
    assert [p.path for p in none.paths] == [p.path for p in two.paths]
    # no work left after the plan: nothing is forecast, nothing else changes
    late = dataclasses.replace(none, elapsed_ms=1e6)
    spent = Budget(work=1.0)
    spent.spend("recognition_update")
    assert with_forecast(late, session, 2, spent).paths == late.paths


def test_forecast_of_nothing():
    session = Session(object_set("thesis_like"), BOUNDS[0], WORKSPACE)
    path = SensingPath((WORKSPACE.radius, 0.0), (-1.0, 0.0), 2 * WORKSPACE.radius)
    assert forecast_distinguishing(session, path) is None
    with pytest.raises(Exception, match="forecast"):
        StrategyConfig(forecast=-1)


def _ellipse_touched(steps: int = 4) -> Session:
    """A world of the shared curved set (the ellipse, from a simulated trial at the
    5 degree sensor) after a miss and up to three contacts (`steps` in all): 15
    classes after two contacts, 7 after three, where no path is informative for
    the outcome model (every hit on the drawn curve has faces of other normals
    within its error disks' reach)."""
    from planner.types import Contact, Observation, Workspace

    models = [m for m in object_set("curved") if len(m.stable_poses[0].outline) <= 500]
    session = Session(models, SensorBounds(1.0, math.radians(5)), Workspace((0, 0), 200))
    taken = [
        ((200.0, 0.0), (-1.0, 0.0), 400.0, None),
        (
            (-17.4311, -199.2389), (0.0871557, 0.9961947), 400.0,
            ((-7.05851, -81.40478), (0.1565347, -0.9876725)),
        ),
        (
            (-54.9538, 192.3021), (0.1565347, -0.9876725), 397.0672,
            ((-22.04934, -15.92739), (-0.5430004, 0.8397324)),
        ),
        (
            (174.0837, -98.4625), (-0.9109793, 0.4124520), 212.3509,
            ((52.42617, -43.32295), (0.8524425, -0.5228211)),
        ),
    ]  # fmt: skip
    for origin, direction, length, contact in taken[:steps]:
        met = None if contact is None else Contact(*contact)
        session = session.observe(Observation(SensingPath(origin, direction, length), met))
    return session


def test_with_nothing_informative_the_recognition_ranks_the_paths():
    """No path informative for the outcome model: the plan ranks the candidates on
    the recognition's predictions, says so, and its best path is sure to leave one
    class by them."""
    session = _ellipse_touched()
    assert len({h.equivalence_class for h in session.hypotheses}) > 1
    found = plan_session(session, (174.08, -98.46), StrategyConfig(budget_ms=None), 0)
    assert found.paths
    first = found.paths[0]
    assert first.scored_by == "recognition"
    assert "no informative path" in (found.note or "")
    assert "ranked on the recognition's predictions" in (found.note or "")
    assert first.p_forecast is not None and first.p_forecast > 0.5


def _plate_in_eight_classes() -> Session:
    """The twins plate touched twice from below and once from each end, away from
    every feature: its four variants in two half-turns, eight classes alike."""
    from planner.models.library import load_objects
    from planner.types import Contact, Observation

    session = Session(load_objects("twins"), SensorBounds(1.0, math.radians(3.0)), WORKSPACE)
    for origin, direction, point, normal in [
        ((-20, -200), (0, 1), (-20, -30), (0, -1)),
        ((20, -200), (0, 1), (20, -30), (0, -1)),
        ((-200, -20), (1, 0), (-60, -20), (-1, 0)),
        ((200, -20), (-1, 0), (60, -20), (1, 0)),
    ]:
        path = SensingPath(origin, direction, 400.0)
        session = session.observe(Observation(path, Contact(point, normal)))
    return session


@pytest.mark.parametrize("sampled", [8, 4])
def test_where_the_recognition_ranks_alone_its_forecast_weighs_every_class(monkeypatch, sampled):
    """Eight classes, nothing informative for the outcome model: the recognition
    judges all eight, and the plan's p_forecast is the forecast over every class
    (a path settling one of eight equal classes: 1/8); from a sample of four it
    would claim 1/4 (renormalized), so the plan's forecast judges every class."""
    monkeypatch.setattr(plan_module, "SHORTLIST_CLASSES_ALONE", sampled)
    session = _plate_in_eight_classes()
    assert len({h.equivalence_class for h in session.hypotheses}) == 8
    found = plan_session(session, (200.0, 0.0), StrategyConfig(budget_ms=None), 0)
    first = found.paths[0]
    assert first.scored_by == "recognition" and "no informative path" in (found.note or "")
    with predictions():
        whole = forecast_distinguishing(session, first.path)
    assert whole is not None and first.p_forecast == pytest.approx(whole)
    assert first.p_forecast == pytest.approx(1 / 8)


def test_a_weak_best_path_gives_way_to_the_recognitions_ranking(monkeypatch):
    """When the outcome model's best path would change the hypotheses only rarely
    (under the weak share, raised here so that the ellipse after one contact,
    where the best changes them with probability 0.33, counts as weak), the plan
    ranks the candidates on the recognition's predictions instead and says so
    (``pdm``: it ranks on the outcome model otherwise)."""
    from planner.planning import plan as plan_module

    session = _ellipse_touched(2)
    now = len({h.equivalence_class for h in session.hypotheses})
    config = StrategyConfig(name="pdm", budget_ms=None)
    assert plan_session(session, (174.08, -98.46), config, 0).paths[0].scored_by == (
        "outcome_model"
    )
    monkeypatch.setattr(plan_module, "_WEAK", 1.01)
    found = plan_session(session, (174.08, -98.46), config, 0)
    assert found.paths and found.paths[0].scored_by == "recognition"
    assert "changes the hypotheses with probability" in (found.note or "")
    expected = float(found.note.split(f"classes {now} -> ")[1].split(" expected")[0])
    assert expected < now


def _curved_touched() -> Session:
    """A world of the shared curved set (no part over 500 vertices) at the 5 degree
    sensor after three contacts (a simulated trial): 7 classes, where the outcome
    model's best path is predicted by the recognition to leave 4 of them and
    another path to leave one."""
    from planner.types import Contact, Observation, Workspace

    models = [m for m in object_set("curved") if len(m.stable_poses[0].outline) <= 500]
    session = Session(models, SensorBounds(1.0, math.radians(5)), Workspace((0, 0), 200))
    taken = [
        (
            (200.0, 0.0), (-1.0, 0.0), 400.0,
            ((-24.6547468, 0.0723040), (0.9984610, 0.0554585)),
        ),
        (
            (-200.0, 0.0), (0.9999018, 0.0140146), 173.8832532,
            ((-96.4238150, 1.4408396), (-0.8893482, 0.4572304)),
        ),
        (
            (141.4213562, 141.4213562), (-0.8146460, -0.5799585), 281.4440310,
            ((-30.3080637, 19.2767093), (0.8576426, 0.5142462)),
        ),
    ]  # fmt: skip
    for origin, direction, length, contact in taken:
        session = session.observe(
            Observation(SensingPath(origin, direction, length), Contact(*contact))
        )
    return session


@pytest.mark.parametrize("strategy", ["lookahead", "optimal"])
def test_lookahead_takes_the_recognitions_ranking_when_it_predicts_better(monkeypatch, strategy):
    """``lookahead`` (and ``optimal``, over the same model) judges the outcome
    model's best path with the recognition before the shortlist, and takes the
    recognition's ranking when it predicts a path that does better (here P(DM) 0
    -> 0.99); without that rule (or as ``pdm``) the outcome model's ranking stands."""
    session = _curved_touched()
    where = (141.42, 141.42)
    # no work budget: how the budget cuts the judging is the next test's
    config = StrategyConfig(name=strategy, budget_ms=None, budget_work=None)
    found = plan_session(session, where, config, 0)
    assert found.paths and found.paths[0].scored_by == "recognition"
    note = found.note or ""
    assert "predicts a better path than the outcome model's best" in note
    p_model = float(note.split("(P(DM) ")[1].split(",")[0])
    assert found.paths[0].p_forecast is not None and found.paths[0].p_forecast > p_model
    monkeypatch.setattr(plan_module, "PREDICTED_FIRST", ())
    plain = plan_session(session, where, config, 0)
    assert plain.paths[0].scored_by == "outcome_model"
    assert plain.paths[0].path != found.paths[0].path


def test_a_plan_whose_budget_is_spent_does_not_ask_the_recognition(monkeypatch):
    """The scene where the recognition's ranking is taken, with the work spent by
    the search: only the outcome model's best path could still be judged, so
    nothing could replace it, and the recognition is not asked."""
    session = _curved_touched()
    asked = []
    judge, rank = plan_module.recognition_ranking, plan_module.rank_candidates

    def spent(*args, **kwargs):
        ranking = rank(*args, **kwargs)
        kwargs["budget"].spend("recognition_update", 1e9)
        return ranking

    monkeypatch.setattr(plan_module, "rank_candidates", spent)
    monkeypatch.setattr(
        plan_module, "recognition_ranking", lambda *a, **k: asked.append(1) or judge(*a, **k)
    )
    found = plan_session(session, (141.42, 141.42), StrategyConfig(budget_ms=None), 0)
    assert found.paths and found.paths[0].scored_by == "outcome_model"
    assert found.stopped_by == "work"
    assert not asked


def _block_in_four_classes() -> Session:
    """The bump block of Exp. II touched twice at the 5-degree sensor (world 184 of
    the README's column, as ``optimal`` touched it): four classes left."""
    from planner.models.library import load_objects
    from planner.types import Contact, Observation, Workspace

    session = Session(
        load_objects("bump_block"), SensorBounds(1.0, math.radians(5)), Workspace((0, 0), 200)
    )
    taken = [
        (
            (200.0, 0.0), (-1.0, 0.0), 400.0,
            ((41.9311906, -0.0351444), (0.9702907, -0.2419422)),
        ),
        (
            (49.0614835, 193.8890684), (-0.2419422, -0.9702907), 399.9975922,
            ((12.7703057, 48.0972761), (0.2256881, 0.9741996)),
        ),
    ]  # fmt: skip
    for origin, direction, length, contact in taken:
        session = session.observe(
            Observation(SensingPath(origin, direction, length), Contact(*contact))
        )
    return session


def test_a_best_path_valued_on_groups_it_cannot_split_is_judged(monkeypatch):
    """``optimal``'s best path: the model is sure of every outcome, but values it one
    touch because each outcome ends in a group of classes no candidate splits
    (P(DM) 0). The recognition judges it, predicts it leaves two classes of four,
    and a path leaving 1.69 replaces it; without the rule the model's path stands
    and the recognition is not asked."""
    session = _block_in_four_classes()
    assert len({h.equivalence_class for h in session.hypotheses}) == 4
    asked = []
    judge = plan_module.recognition_ranking
    monkeypatch.setattr(
        plan_module, "recognition_ranking", lambda *a, **k: asked.append(1) or judge(*a, **k)
    )
    # the sensor where the tied paths of least motion are ones the recognition judges
    # weak (from where it last touched, the model's tie goes to a path that is not)
    where, config = (-200.0, 0.0), StrategyConfig(name="optimal", budget_ms=None)
    found = plan_session(session, where, config, 0)
    assert "predicts a better path than the outcome model's best" in (found.note or "")
    assert found.paths[0].scored_by == "recognition"
    asked.clear()
    monkeypatch.setattr(plan_module, "_settles_short", lambda *a: False)
    plain = plan_session(session, where, config, 0)
    assert not asked and plain.paths[0].scored_by == "outcome_model"
    assert plain.paths[0].expected_remaining == pytest.approx(1.0)
    assert plain.paths[0].p_distinguishing < 1


def test_where_the_outcome_model_is_sure_its_ranking_stands(monkeypatch):
    """The same scene, with the outcome model made sure of every outcome: its best
    path is the recognition's nominal prediction looked at two touches deep, so
    ``lookahead`` keeps it and the recognition is not asked."""
    from planner.planning import forecast
    from planner.planning.outcomes import Outcomes

    session = _curved_touched()
    asked = []
    judge = forecast.recognition_ranking
    monkeypatch.setattr(
        plan_module, "recognition_ranking", lambda *a, **k: asked.append(1) or judge(*a, **k)
    )
    monkeypatch.setattr(Outcomes, "uncertain_on", lambda o, rows: np.zeros_like(o.hit[rows]))
    found = plan_session(session, (141.42, 141.42), StrategyConfig(budget_ms=None), 0)
    assert found.paths and found.paths[0].scored_by == "outcome_model"
    assert not asked


def test_with_exact_sensing_the_outcome_models_ranking_stands(monkeypatch):
    """Exact sensing: the outcome model's uncertain zones are its rounding slack,
    so ``lookahead`` keeps its ranking even where it calls an outcome of its best
    path uncertain, and the recognition is not asked."""
    from planner.planning import forecast
    from planner.planning.outcomes import Outcomes

    session = touched("thesis_like", BOUNDS[0], 3, 2)
    assert session.status == "ambiguous"
    asked = []
    judge = forecast.recognition_ranking
    monkeypatch.setattr(
        plan_module, "recognition_ranking", lambda *a, **k: asked.append(1) or judge(*a, **k)
    )
    monkeypatch.setattr(Outcomes, "uncertain_on", lambda o, rows: np.ones_like(o.hit[rows]))
    found = plan_session(session, SENSOR, StrategyConfig(budget_ms=None), 0)
    assert found.paths and found.paths[0].scored_by == "outcome_model"
    assert not asked


def testoutcomes_apart_measures_in_error_bounds():
    from types import SimpleNamespace

    from planner.planning.forecast import outcomes_apart

    nan = np.nan
    out = SimpleNamespace(
        hit=np.array([[True, True], [True, False], [False, False], [True, True]]),
        point=np.array(
            [
                [[0.0, 0.0], [3.0, 0.0]],
                [[0.0, 0.0], [nan, nan]],
                [[nan, nan], [nan, nan]],
                [[1.0, 1.0], [1.0, 1.0]],
            ]
        ),
        normal=np.array(
            [
                [[1.0, 0.0], [1.0, 0.0]],
                [[1.0, 0.0], [nan, nan]],
                [[nan, nan], [nan, nan]],
                [[1.0, 0.0], [0.0, 1.0]],
            ]
        ),
    )
    apart = outcomes_apart(out, np.arange(4), np.array([0, 1]), SensorBounds(1.0, 0.1))
    np.testing.assert_allclose(apart[[0, 2, 3]], [3.0, 0.0, (math.pi / 2) / 0.1])
    assert apart[1] == np.inf  # a hit against a miss


def test_the_shortlist_grows_while_no_path_is_predicted_to_change_anything(monkeypatch):
    """The recognition judges `SHORTLIST` paths, and more (up to SHORTLIST_ROUNDS
    times as many) while none of them is predicted to change the classes."""
    from planner.planning import forecast
    from planner.planning.analysis import analyse

    session = _ellipse_touched()
    found = analyse(
        session.hypotheses, session.models, session.working_sensor, session.workspace,
        (174.08, -98.46), StrategyConfig(),
    )  # fmt: skip
    current = found.posed.n_classes
    judged: list[int] = []

    def classes_after(session, path, out, c, h):
        if c not in judged:
            judged.append(c)
        return 1 if len(judged) > forecast.SHORTLIST + 2 else current

    monkeypatch.setattr(forecast, "classes_after", classes_after)
    ranking = forecast.recognition_ranking(session, found)
    assert len(judged) == forecast.SHORTLIST + 3
    assert ranking.expected_classes[0] < current
    # when the first paths already change something, no more are judged
    judged.clear()
    monkeypatch.setattr(forecast, "classes_after", lambda *a: 1)
    assert len(forecast.recognition_ranking(session, found).rows) == forecast.SHORTLIST
    # until sure: a path predicted to leave one class whatever the truth ends the
    # judging (judged first here, or the first after it)
    first = int(ranking.rows[-1])
    sure = forecast.recognition_ranking(session, found, first=[first], until_sure=True)
    assert sure.rows.tolist() == [first]
    assert len(forecast.recognition_ranking(session, found, first=[first]).rows) > 1
    monkeypatch.setattr(forecast, "classes_after", lambda s, p, o, c, h: 2 if c == first else 1)
    sure = forecast.recognition_ranking(session, found, first=[first], until_sure=True)
    assert len(sure.rows) == 2 and sure.rows[1] == first


def test_a_predicted_observation_is_observed_once_per_plan(monkeypatch):
    session = touched("thesis_like", BOUNDS[1], 3, 2)
    found = analysed(session)
    path = found.candidates.path(0)
    with predictions():
        first = observed(session, path, found.outcomes, 0, 0)
        assert observed(session, path, found.outcomes, 0, 0) is first
    again = observed(session, path, found.outcomes, 0, 0)  # no plan: no memo
    assert again is not first and again.hypotheses == first.hypotheses
    # the memo saves updates, never changes a plan
    config = StrategyConfig(forecast=3)
    remembered = plan_session(session, SENSOR, config, 0)
    monkeypatch.setattr(plan_module, "predictions", contextlib.nullcontext)
    forgotten = plan_session(session, SENSOR, config, 0)
    assert remembered.paths == forgotten.paths and remembered.work == forgotten.work


def test_a_forecast_the_budget_cannot_finish_is_not_begun():
    session = touched("thesis_like", BOUNDS[1], 3, 2)
    classes = len({h.equivalence_class for h in session.hypotheses})
    assert classes > 2
    path = analysed(session).candidates.path(0)
    whole = forecast_distinguishing(session, path)
    each = UNIT_US["recognition_update"] + update_size(session) * UNIT_US["recognition_hypothesis"]
    # the last class' update starts within the budget: the forecast is made
    enough = Budget(work=(classes - 1) * each + 1.0)
    assert forecast_distinguishing(session, path, enough) == whole
    # one class short: nothing is spent on a forecast that would say nothing
    short = Budget(work=(classes - 1) * each - 1.0)
    assert forecast_distinguishing(session, path, short) is None
    assert short.units == 0.0 and short.stopped_by == "work"


def test_the_recognition_ranks_a_halving_path_before_one_that_settles_a_class(monkeypatch):
    """Eight equal classes: a path that leaves four whatever the truth (log 4 nats
    of classes left) ranks before one that settles one truth and leaves seven for
    the rest (P(DM) 1/8, 7/8 log 7), though the second has the larger P(DM)."""
    from planner.planning import forecast
    from planner.planning.analysis import analyse

    session = _plate_in_eight_classes()
    found = analyse(
        session.hypotheses, session.models, session.working_sensor, session.workspace,
        (200.0, 0.0), StrategyConfig(),
    )  # fmt: skip
    calls: dict[int, int] = {}
    order: list[int] = []

    def classes_after(session, path, out, c, h):
        calls[c] = calls.get(c, 0) + 1
        if c not in order:
            order.append(c)
        if order.index(c) == 0:  # the first path judged settles the first truth
            return 1 if calls[c] == 1 else 7
        return 4 if order.index(c) == 1 else 8  # the second halves; the rest nothing

    monkeypatch.setattr(forecast, "classes_after", classes_after)
    ranking = forecast.recognition_ranking(session, found, classes=8)
    peel, halve = order[0], order[1]
    assert ranking.rows[0] == halve and ranking.rows[1] == peel
    assert ranking.p_distinguishing[1] == pytest.approx(1 / 8)
    assert ranking.expected_log[0] == pytest.approx(math.log(4))
    assert ranking.expected_log[1] == pytest.approx(7 / 8 * math.log(7))


def test_a_path_ahead_only_by_its_logarithm_does_not_replace_the_models_best(monkeypatch):
    """A D shape alone, a required accuracy of 1 mm, the touches `lookahead`
    chose (two misses, then a hit): the recognition ranks a path ahead of the
    outcome model's best by the expected logarithm of the classes left while none
    of the paths it judged is predicted to leave fewer classes (some truths would
    split a class). The plan keeps the model's ranking; it used to fail looking
    for the first path predicted to leave fewer (an error, a 500 over HTTP). The
    scene's own judging now finds such a path, so the judged paths' predictions
    are set to leave as many classes as there are: the recognition still ranks
    another path first, by the logarithm alone."""
    from planner.codec import observation_from_dict
    from planner.types import Accuracy

    real, ahead = plan_module.recognition_ranking, []

    def none_leaves_fewer(session, found, *args, **kwargs):
        judged = real(session, found, *args, **kwargs)
        if kwargs.get("first"):  # the model's best judged first
            ahead.append(int(judged.rows[0]) != int(kwargs["first"][0]))
        stay = np.full(len(judged.rows), float(judged.current))
        return dataclasses.replace(judged, expected_classes=stay)

    monkeypatch.setattr(plan_module, "recognition_ranking", none_leaves_fewer)

    models = [m for m in object_set("curved") if m.name == "d_shape"]
    origin, side = [184.91893179950094, 76.19047619047619], [-1.0, 6.123233995736766e-17]
    observations = [
        {"path": {"origin": [200.0, 0.0], "direction": [-1.0, -0.0], "length": 400.0}},
        {
            "path": {
                "origin": [origin[0], -origin[1]],
                "direction": side,
                "length": 369.8378635990019,
            }
        },
        {
            "path": {"origin": origin, "direction": side, "length": 369.8378635990019},
            "contact": {
                "point": [102.05126670288982, 76.16004539827351],
                "normal": [0.5851089474633733, 0.8109546963908055],
            },
        },
    ]
    session = Session(models, BOUNDS[1], WORKSPACE, accuracy=Accuracy(1.0, 0.05))
    for o in observations:
        session = session.observe(observation_from_dict({"contact": None, **o}))
    found = plan_session(session, (200.0, 0.0), StrategyConfig(name="lookahead", budget_ms=None), 3)
    assert ahead and ahead[0]  # the recognition put another path first
    assert found.paths and found.paths[0].scored_by == "outcome_model"
    assert "predicts a better path" not in (found.note or "")


@pytest.mark.parametrize("name", ["thesis_like", "twins"])
@settings(max_examples=8, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), touches=st.integers(1, 3))
def test_the_shortlists_screen_counts_between_one_class_and_all(name, seed, touches):
    """The screen's guess at the expected log of the classes left lies between
    none split (log of the classes) and every one (0); a path every class misses
    splits none; wider sensor bounds keep at least as many classes."""
    from planner.planning.screen import screened_log

    session = touched(name, BOUNDS[1], seed, touches)
    if session.status != "ambiguous":
        return
    found = analysed(session)
    posed, out = found.posed, found.outcomes
    top = np.argsort(-posed.class_weight, kind="stable")[:4]
    weight = posed.class_weight[top] / posed.class_weight[top].sum()
    rows = np.arange(len(found.candidates.source))
    screen = screened_log(out, rows, posed, top, weight, BOUNDS[1])
    assert np.all(screen >= -1e-12) and np.all(screen <= math.log(posed.n_classes) + 1e-9)
    missed = ~out.hit.any(axis=1)
    np.testing.assert_allclose(screen[missed], math.log(posed.n_classes))
    wider = screened_log(out, rows, posed, top, weight, SensorBounds(3.0, math.radians(9)))
    assert np.all(wider >= screen - 1e-12)


def test_the_screen_keeps_a_class_whose_outline_passes_the_contact_facing_it():
    """Class 0 (a square) predicts a contact on its left face; class 1, the square
    moved 1.5 mm right, keeps it at 1 mm (its outline within two position bounds,
    its face turned alike) and loses it at 0.5 mm; class 2, the square turned a
    half-turn about a point 100 mm off, lies far and loses it; class 3, a square
    whose right face passes 0.5 mm from the contact facing away from it, loses
    it; a miss keeps the classes that miss."""
    from types import SimpleNamespace

    from planner.planning.posed_set import PosedSet
    from planner.planning.screen import screened_log

    square = np.array([[-10.0, -10], [10, -10], [10, 10], [-10, 10]])
    normals = np.array([[0.0, -1], [1, 0], [0, 1], [-1, 0]])

    def faces(shift):
        return square + shift, np.roll(square, -1, axis=0) + shift, normals

    rings = [faces((0.0, 0.0)), faces((1.5, 0.0)), faces((200.0, 0.0)), faces((-19.5, 0.0))]
    posed = SimpleNamespace(
        start=np.stack([r[0] for r in rings]),
        end=np.stack([r[1] for r in rings]),
        normal=np.stack([r[2] for r in rings]),
        valid=np.ones((4, 4), bool),
        cls=np.arange(4),
        weight=np.array([0.4, 0.3, 0.2, 0.1]),
        class_weight=np.array([0.4, 0.3, 0.2, 0.1]),
        n_classes=4,
    )
    posed.best_members = lambda classes: PosedSet.best_members(posed, classes)
    nan = np.nan
    out = SimpleNamespace(  # path 0 hits the left faces from the left, path 1 misses all
        hit=np.array([[True, True, False, True], [False, False, False, False]]),
        point=np.array([[[-10.0, 0.0], [-8.5, 0.0], [nan, nan], [-9.5, 0.0]], [[nan, nan]] * 4]),
        normal=np.array([[[-1.0, 0.0], [-1.0, 0.0], [nan, nan], [1.0, 0.0]], [[nan, nan]] * 4]),
    )
    top, one = np.array([0]), np.array([1.0])
    loose = screened_log(out, np.arange(2), posed, top, one, SensorBounds(1.0, 0.05))
    tight = screened_log(out, np.arange(2), posed, top, one, SensorBounds(0.5, 0.05))
    np.testing.assert_allclose(loose, [math.log(2), math.log(4)])
    np.testing.assert_allclose(tight, [0.0, math.log(4)])


def test_the_screen_counts_only_the_classes_its_budget_pays_for(monkeypatch):
    """Each (path, predicting class, counted class' face) costs a `screen_face`
    unit: the screen counts as many of the most probable classes as the budget
    affords (or its floor pays for) and spends for them; affording none, it
    leaves the order as given (all zeros) and spends nothing."""
    from planner.planning import screen
    from planner.planning.budget import UNIT_US

    session = touched("thesis_like", BOUNDS[1], 4, 1)
    found = analysed(session)
    posed, out = found.posed, found.outcomes
    assert posed.n_classes > 3
    top = np.argsort(-posed.class_weight, kind="stable")[:4]
    weight = posed.class_weight[top] / posed.class_weight[top].sum()
    rows = np.arange(len(found.candidates.source))
    order = np.argsort(-posed.class_weight, kind="stable")[: screen.SCREEN_CLASSES]
    faces = posed.valid[posed.best_members(order)].sum(axis=1)
    cells = len(rows) * len(top) * np.cumsum(faces)
    free = screen.screened_log(out, rows, posed, top, weight, BOUNDS[1])
    # a spent budget: the floor pays for the screen (here every class fits in it)
    spent = Budget(work=0.0)
    floor = screen.screened_log(out, rows, posed, top, weight, BOUNDS[1], spent)
    assert cells[-1] * UNIT_US["screen_face"] <= screen.SCREEN_FLOOR
    np.testing.assert_array_equal(floor, free)
    assert spent.spent["screen_face"] == cells[-1]
    monkeypatch.setattr(screen, "SCREEN_FLOOR", 0.0)
    poor = Budget(work=0.5 * cells[0] * UNIT_US["screen_face"])
    assert np.all(screen.screened_log(out, rows, posed, top, weight, BOUNDS[1], poor) == 0)
    assert poor.units == 0
    three = Budget(work=(cells[2] + 1) * UNIT_US["screen_face"])
    some = screen.screened_log(out, rows, posed, top, weight, BOUNDS[1], three)
    assert three.spent["screen_face"] == cells[2]
    # classes left uncounted survive every outcome: the guess splits no more
    assert np.all(some >= free - 1e-12)
