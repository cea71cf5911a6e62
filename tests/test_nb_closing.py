"""Notebook 06's support module: Exercise 3's verdict flips with the numbers it is given (judged
against the per-start standard errors), every sentence reads the numbers it is given, every figure
draws with labelled axes, and every self-check is well formed. All inputs are small synthetic
dicts with the keys ``pusht.loop`` and ``metrics.json`` write; no run's files are read."""

import math

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.figure import Figure

from pusht.env import OBS_NAMES
from pusht.nb import closing as nb06
from pusht.selfcheck import Question, render

N = 30


def labelled(fig):
    assert isinstance(fig, Figure)
    axes = [ax for ax in fig.axes if ax.get_visible() and ax.axison]
    assert axes and all(ax.get_xlabel() for ax in axes) and all(ax.get_ylabel() for ax in axes)
    assert all(ax.get_title() for ax in axes)


def metrics(dream=-0.215, real=-0.400, se=0.020, dream_tr=-0.285, real_tr=-0.400, se_tr=0.011, success=0,
            touches=3, moved=0.003, moved_max=0.06, toward=0.002, final=0.155, wall=0.87, drift=0.23,
            drift_se=0.022, training_tr=0.007, training_tr_se=0.009, yaw_frac=0.6, expert_dream=-0.065,
            expert_dream_se=0.019, expert_real=0.168, zero_dream=0.061, **extra):
    """One run's metrics, both worlds consistent: every gap is the dream's rating minus reality's, and
    its yaw half (``yaw_frac`` of it) plus its position half is the gap."""
    m = {"seed": 0, "eval_episodes": N, "eval_horizon": 100,
         "imagined_return_per_step": dream, "real_return_per_step": real,
         "trained_dream_return_per_step_eval_horizon": dream, "trained_real_return_per_step_eval_horizon": real,
         "trained_dream_return_per_step_train_horizon": dream_tr, "trained_real_return_per_step_train_horizon": real_tr,
         "imagination_gap": dream - real, "imagination_gap_eval_horizon": dream - real,
         "imagination_gap_se_eval_horizon": se, "imagination_gap_train_horizon": dream_tr - real_tr,
         "imagination_gap_se_train_horizon": se_tr,
         "real_success_rate": success / N, "real_episodes_touching_block": touches,
         "real_block_displacement": moved, "real_block_displacement_max": moved_max,
         "real_block_toward_target": toward, "real_final_tee_dist": final, "spawn_tee_dist": 0.158,
         "real_pusher_at_wall_share": wall,
         "gap_drift_eval_horizon": drift, "gap_drift_se_eval_horizon": drift_se,
         "gap_training_train_horizon": training_tr, "gap_training_se_train_horizon": training_tr_se,
         "zero_action_dream_final_tee_dist": zero_dream, "expert_real_success_rate": 1.0}
    m.update(extra)
    for span, se_ in (("train_horizon", m["imagination_gap_se_train_horizon"]),
                      ("eval_horizon", m["imagination_gap_se_eval_horizon"])):
        g = m[f"imagination_gap_{span}"]
        m.setdefault(f"imagination_gap_yaw_{span}", yaw_frac * g)
        m.setdefault(f"imagination_gap_position_{span}", g - m[f"imagination_gap_yaw_{span}"])
        m.setdefault(f"imagination_gap_se_yaw_{span}", se_ * 0.8)
        m.setdefault(f"imagination_gap_se_position_{span}", se_ * 0.7)
        m.setdefault(f"expert_signal_dream_{span}", expert_dream)
        m.setdefault(f"expert_signal_dream_se_{span}", expert_dream_se)
        m.setdefault(f"expert_signal_real_{span}", expert_real)
        m.setdefault(f"expert_signal_real_se_{span}", 0.014)
    m.setdefault("gap_drift_yaw_eval_horizon", 0.6 * m["gap_drift_eval_horizon"])
    m.setdefault("gap_drift_position_eval_horizon", m["gap_drift_eval_horizon"] - m["gap_drift_yaw_eval_horizon"])
    m.setdefault("gap_drift_se_yaw_eval_horizon", 0.8 * m["gap_drift_se_eval_horizon"])
    m.setdefault("gap_drift_se_position_eval_horizon", 0.7 * m["gap_drift_se_eval_horizon"])
    # the size of each error and |yaw| - |position|, with per-start standard errors (split.size_split):
    # where the halves share a sign, the size is the gap's size and its standard error the gap's
    for key, spans in (("imagination_gap", ("train_horizon", "eval_horizon")), ("gap_drift", ("eval_horizon",))):
        for span in spans:
            p_, y_ = m[f"{key}_position_{span}"], m[f"{key}_yaw_{span}"]
            pse, yse = m[f"{key}_se_position_{span}"], m[f"{key}_se_yaw_{span}"]
            whole_se = m[f"{key}_se_{span}"]
            m.setdefault(f"{key}_size_{span}", abs(p_) + abs(y_))
            m.setdefault(f"{key}_size_se_{span}", whole_se if p_ * y_ >= 0 else math.hypot(pse, yse))
            m.setdefault(f"{key}_yaw_minus_position_{span}", abs(y_) - abs(p_))
            m.setdefault(f"{key}_yaw_minus_position_se_{span}", math.hypot(pse, yse))
    # each world's rating with its own per-start standard error: reality's varies far less than the dream's
    for span in ("train_horizon", "eval_horizon"):
        m.setdefault(f"trained_dream_return_per_step_se_{span}", m[f"imagination_gap_se_{span}"])
        m.setdefault(f"trained_real_return_per_step_se_{span}", 0.003)
        # zero actions in the real sim: the same starts, the same rating in every round
        m.setdefault(f"zero_real_return_per_step_{span}", -0.400)
        m.setdefault(f"zero_real_return_per_step_se_{span}", 0.003)
    # the zero-action control: reality's zero-action rating is the same in every run (the same starts), the
    # dream's is that plus the drift
    m.setdefault("zero_action_dream_return_per_step", -0.45 + m["gap_drift_eval_horizon"])
    for span in ("train_horizon", "eval_horizon"):
        m.setdefault(f"zero_dream_block_moved_{span}", 0.01)
        m.setdefault(f"expert_gap_{span}", -0.2)
        m.setdefault(f"expert_gap_se_{span}", 0.02)
    return m


def model_errors(policy_block=0.064, policy_pusher=0.117, expert_block=0.014, expert_pusher=0.021,
                 ol_policy=(0.13, 0.14), ol_expert=(0.035, 0.058), policy_copy_block=0.0005, expert_copy_block=0.0086):
    e = {"wm_policy_one_step_block_err": policy_block, "wm_policy_one_step_block_copy_err": policy_copy_block,
         "wm_policy_one_step_pusher_err": policy_pusher, "wm_policy_one_step_pusher_copy_err": 0.010,
         "wm_expert_one_step_block_err": expert_block, "wm_expert_one_step_block_copy_err": expert_copy_block,
         "wm_expert_one_step_pusher_err": expert_pusher, "wm_expert_one_step_pusher_copy_err": 0.035}
    for data, (blk, push) in (("policy", ol_policy), ("expert", ol_expert)):
        e[f"wm_{data}_open_loop_block_err"], e[f"wm_{data}_open_loop_pusher_err"] = blk, push
        e[f"wm_{data}_open_loop_block_copy_err"] = 0.04 if data == "expert" else 0.003
        e[f"wm_{data}_open_loop_pusher_copy_err"] = 0.21 if data == "expert" else 0.08
    return e


def loop(gaps_dreams, reals=None, successes=None, errors=None, se=0.020, **last_extra):
    """Rounds 0.. with the given dream ratings (and real ratings, successes, model errors)."""
    k = len(gaps_dreams)
    reals = reals or [-0.400] * k
    successes = successes or [0] * k
    errors = errors or [model_errors(0.064 / (r + 1) ** 2, 0.117 / (r + 1) ** 2) for r in range(k)]
    rounds = []
    for r in range(k):
        m = metrics(dream=gaps_dreams[r], real=reals[r], se=se, success=successes[r],
                    **(last_extra if r == k - 1 else {}))
        m.update(errors[r], round=r, policy_episodes=60 * r, train_clips=300 + 360 * r)
        rounds.append(m)
    return rounds


# --- the statistics ------------------------------------------------------------------------------
def test_a_change_is_judged_against_both_standard_errors():
    c = nb06.compare(0.185, 0.020, 0.031, 0.021, N)
    assert c.diff == pytest.approx(-0.154) and c.se == pytest.approx(math.hypot(0.020, 0.021))
    assert c.k == pytest.approx(2.045, abs=2e-3) and c.df == 29 and c.outcome == "down"
    assert c.shrank and not c.grew
    # the same difference with wide noise does not count
    wide = nb06.compare(0.185, 0.06, 0.031, 0.06, N)
    assert wide.outcome == "same" and not wide.shrank and wide.ratio < wide.k
    # through zero and out the other side, larger: it moved, but did not shrink; it grew
    flip = nb06.compare(0.185, 0.02, -0.30, 0.02, N)
    assert flip.outcome == "down" and not flip.shrank and flip.grew and flip.crossed
    # through zero, ending smaller but beyond the noise on the other side: a change of sign, not a shrink
    cross = nb06.compare(0.185, 0.02, -0.05, 0.02, N)
    assert cross.crossed and not cross.shrank
    # through zero, ending within the noise of zero: a shrink
    near = nb06.compare(0.185, 0.02, -0.03, 0.02, N)
    assert near.shrank and not near.crossed
    # beyond the noise but smaller than the minimum effect: detected, does not count
    tiny = nb06.compare(0.100, 0.001, 0.090, 0.001, N, min_effect=nb06.MIN_REWARD_EFFECT)
    assert tiny.detected and not tiny.matters and tiny.outcome == "same" and not tiny.shrank
    assert nb06.compare(0.100, 0.001, 0.090, 0.001, N).shrank                  # without a minimum effect
    assert "minimum effect that matters 0.020" in tiny.why() and "t-test" in tiny.why()
    # fewer starts, larger k
    assert nb06.compare(0, 1, 1, 1, 5).k > nb06.compare(0, 1, 1, 1, 30).k
    assert nb06.compare(0.1, 0.0, 0.1, 0.0, N).outcome == "same"


def test_gap_change_reads_round_zero_and_the_last_round():
    rounds = loop([-0.215, -0.214, -0.332, -0.387])
    c = nb06.gap_change(rounds)
    assert c.first == pytest.approx(0.185) and c.last == pytest.approx(0.013)
    assert c.min_effect == nb06.MIN_REWARD_EFFECT
    t = nb06.gap_change(rounds, "train_horizon")
    assert t.first == pytest.approx(rounds[0]["imagination_gap_train_horizon"])
    with pytest.raises(ValueError, match="round 0 and at least one"):
        nb06.gap_change(rounds[:1])
    with pytest.raises(ValueError, match="span"):
        nb06.gap_change(rounds, "whole")


def test_fisher_counts():
    assert nb06.count_rise_p(0, 0, N) == pytest.approx(1.0)
    assert nb06.count_rise_p(0, 1, N) == pytest.approx(0.5)                 # one event: either round
    assert nb06.count_rise_p(3, 13, N) < nb06.COUNT_P < nb06.count_rise_p(3, 5, N)
    # the hypergeometric tail, by hand: 0 then 2 of 30 each
    assert nb06.count_rise_p(0, 2, N) == pytest.approx(math.comb(30, 2) / math.comb(60, 2))


def test_the_block_bounds_hold_for_any_starts_that_fit_the_metrics():
    rng = np.random.default_rng(0)
    for _ in range(200):
        d = rng.uniform(0, 0.3, N) * (rng.uniform(size=N) < 0.5)           # many blocks never move
        t = d * rng.uniform(-1, 1, N)                                       # |toward| <= displacement
        m = {"eval_episodes": N, "real_block_displacement": d.mean(), "real_block_displacement_max": d.max(),
             "real_block_toward_target": t.mean()}
        assert d.std(ddof=1) / np.sqrt(N) <= nb06.displacement_se_bound(m) + 1e-12
        assert t.std(ddof=1) / np.sqrt(N) <= nb06.toward_se_bound(m) + 1e-12
    m = metrics(moved=0.05, moved_max=0.26, toward=-0.016)
    assert nb06.toward_outcome(m) == "same"                                 # within k bounds
    assert nb06.toward_outcome(metrics(moved=0.05, moved_max=0.06, toward=-0.04)) == "farther"
    assert nb06.toward_outcome(metrics(moved=0.05, moved_max=0.06, toward=0.045)) == "closer"
    assert nb06.toward_outcome(metrics(moved=0.0, moved_max=0.0, toward=0.0)) == "same"


# --- Exercise 3's verdict ------------------------------------------------------------------------
def test_the_verdict_flips_with_the_numbers():
    assert set(nb06.EX3_OPTIONS) == {"a", "b", "c", "d"}
    assert nb06.ex3_verdict(loop([-0.215, -0.387])) == "b"                      # shrinks, no success
    assert nb06.ex3_verdict(loop([-0.215, -0.387], successes=[0, 2])) == "a"    # shrinks, successes
    assert nb06.ex3_verdict(loop([-0.215, -0.230])) == "c"                      # within the noise
    assert nb06.ex3_verdict(loop([-0.215, -0.100], successes=[0, 1])) == "d"    # grows, a success
    assert nb06.ex3_verdict(loop([-0.215, -0.700])) == "c"                      # through zero, larger
    assert nb06.ex3_verdict(loop([-0.215, -0.450])) == "c"                      # through zero, smaller: not a shrink
    assert nb06.ex3_verdict(loop([-0.215, -0.230], se=0.001)) == "c"            # detected, below the minimum effect
    assert nb06.ex3_verdict(loop([-0.215, -0.387], se=0.08)) == "c"             # wide noise swallows it
    # reality rising to the dream closes the gap too
    assert nb06.ex3_verdict(loop([-0.215, -0.215], reals=[-0.400, -0.250])) == "b"


# --- sentences -----------------------------------------------------------------------------------
def test_the_reconciliation_says_from_which_side_the_gap_moved():
    text = nb06.reconcile_text(loop([-0.215, -0.214, -0.332, -0.387]))
    assert "+0.185" in text and "after round 3 +0.013" in text and "conservative" in text
    assert "The gap shrank" in text and "from the dream's side" in text and "dream came down" in text
    assert "minimum effect that matters is 0.02" in text and "smallest in the last round" in text
    assert "Real success stayed at 0%" in text and "answer is (b)" in text
    up = nb06.reconcile_text(loop([-0.215, -0.215], reals=[-0.400, -0.250]))
    assert "from reality's side" in up and "what the policy really earns rose" in up and "Reality rose" in up
    grew = nb06.reconcile_text(loop([-0.215, -0.100], successes=[0, 1]))
    assert "The gap grew" in grew and "Real success rose above 0%" in grew and "could be luck" in grew
    assert "answer is (d)" in grew
    same = nb06.reconcile_text(loop([-0.215, -0.230]))
    assert "did not fall beyond the noise and the minimum effect: it did not shrink" in same
    assert "Neither rating alone" in same
    flip = nb06.reconcile_text(loop([-0.215, -0.700]))
    assert "changed sign" in flip and "The gap grew" in flip
    cross = nb06.reconcile_text(loop([-0.215, -0.450]))
    assert "out the other side" in cross and "changed sign" in cross and "answer is (c)" in cross
    # the gap shrinks, then reopens
    reopened = nb06.reconcile_text(loop([-0.215, -0.400, -0.300, -0.250]))
    assert "smallest in round 1" in reopened and "the gap reopened" in reopened
    # every number comes from the pooled per-step gap (the one with a standard error), never the other
    odd = loop([-0.215, -0.387])
    odd[-1]["imagination_gap"] = 0.555
    assert "0.555" not in nb06.reconcile_text(odd) and "0.555" not in nb06.rounds_table(odd)
    wobble = nb06.reconcile_text(loop([-0.215, -0.380, -0.370]))
    assert "smallest in round 1" in wobble and "not larger beyond the noise" in wobble
    many = nb06.reconcile_text(loop([-0.215, -0.387], successes=[0, 9]))
    assert "beyond chance" in many and "answer is (b)" not in many


def test_a_gap_that_narrows_while_reality_falls_below_doing_nothing_is_called_so():
    # the gap shrinks from +0.185 to +0.040 while what reality pays the policy falls below zero actions' -0.400
    worse = nb06.reconcile_text(loop([-0.215, -0.380, -0.400], reals=[-0.400, -0.425, -0.440]))
    assert "The gap shrank" in worse and "in rounds 1, 2 the policy earned less in reality than a pusher" in worse
    assert "worse than standing still" in worse and "does not mean a better policy" in worse
    # the same shrink with reality level with doing nothing: no such sentence
    level = nb06.reconcile_text(loop([-0.215, -0.380, -0.387], reals=[-0.400, -0.400, -0.401]))
    assert "The gap shrank" in level and "in no round did the policy earn less in reality" in level
    assert "worse than standing still" not in level
    # below doing nothing by less than the minimum effect, or within the noise, does not count
    close = nb06.reconcile_text(loop([-0.215, -0.395], reals=[-0.400, -0.410]))
    assert "in no round" in close
    # below in an early round only: said, but the gap's narrowing is not blamed on it
    early = nb06.reconcile_text(loop([-0.215, -0.420, -0.387], reals=[-0.400, -0.450, -0.400]))
    assert "in round 1 the policy earned less" in early and "worse than standing still" not in early


def test_the_table_has_a_row_per_round_with_its_numbers():
    rounds = loop([-0.215, -0.214, -0.332])
    t = nb06.rounds_table(rounds)
    lines = [ln for ln in t.splitlines() if ln.startswith("| ") and not ln.startswith("| round")]
    assert len(lines) == 3 and "+0.185 ± 0.020" in lines[0] and "87%" in lines[0]
    assert "64.0 / 0.5" in lines[0] and "16.0 / 0.5" in lines[1]            # model / copy-last, mm
    rounds[2]["real_pusher_at_wall_share"] = 0.03
    assert "| 3% |" in nb06.rounds_table(rounds)


def test_the_model_error_sentence_reads_every_round():
    rounds = loop([-0.2] * 4)
    s = nb06.model_error_sentence(rounds)
    assert "a resolution, not a test" in s
    assert "64.0 -> 16.0 -> 7.1 -> 4.0 mm (fell in every round)" in s
    assert "held within 1 mm throughout" in s                                # expert one-step: constant
    errors = [model_errors(b, 0.1 / (r + 1), expert_block=0.01 + 0.002 * r, ol_expert=(0.035 + 0.005 * r, 0.06))
              for r, b in enumerate((0.064, 0.015, 0.0078, 0.0069))]
    s = nb06.model_error_sentence(loop([-0.2] * 4, errors=errors))
    assert "fell in rounds 1 and 2, held within 1 mm in round 3" in s
    assert "rose in every round" in s and "on some it stayed within 1 mm of round 0" in s   # open-loop level
    errors = [model_errors(b, 0.1 / (r + 1), expert_block=0.01 + 0.002 * r, ol_expert=(0.035 + 0.005 * r, 0.06),
                           ol_policy=(0.13 / (r + 1), 0.14 / (r + 1)))
              for r, b in enumerate((0.064, 0.015, 0.0078, 0.0069))]
    s = nb06.model_error_sentence(loop([-0.2] * 4, errors=errors))
    assert "worse, on some measures, on the expert's" in s and "78% of its 1380 training clips" in s
    for e in errors:
        e["wm_expert_one_step_block_err"], e["wm_expert_open_loop_block_err"] = 0.01, 0.035
    assert "without losing ground" in nb06.model_error_sentence(loop([-0.2] * 4, errors=errors))
    errors[-1]["wm_policy_open_loop_block_err"] = 0.2
    s = nb06.model_error_sentence(loop([-0.2] * 4, errors=errors))
    assert "on some it ended worse than in round 0" in s and "rose in round 3" in s
    errors[-1]["wm_policy_one_step_block_err"] = 0.03
    assert "rose in round 3" in nb06.model_error_sentence(loop([-0.2] * 4, errors=errors))


def test_the_block_sentence_reads_touches_and_direction():
    rounds = loop([-0.2, -0.3], touches=13, moved=0.05, moved_max=0.26, toward=-0.016, wall=0.03)
    s = nb06.block_sentence(rounds)
    assert "87%, 3%" in s and "3, 13 of 30" in s and "beyond chance" in s
    assert "0.016 m farther from" in s and "not told apart from where it spawned" in s
    assert "more, beyond the noise" in s and "not toward the target" in s
    s = nb06.block_sentence(loop([-0.2, -0.3], touches=13, moved=0.05, moved_max=0.06, toward=0.045))
    assert "closer, beyond the noise" in s and "toward the target, measurably" in s
    assert "independent samples" in s and "McNemar" in s and "approximation" in s
    assert "k = 2.05" in s and "upper bound on the standard error" in s and "minimum effect of 0.02 m" in s
    s = nb06.block_sentence(loop([-0.2, -0.3], touches=3, moved=0.004, moved_max=0.06, toward=0.0))
    assert "3, 3 of 30 evaluation episodes." in s and "not told apart by these starts" in s
    # beyond the bound on the noise (no spread at all) but 1 cm: below the success tolerance
    small = nb06.block_sentence(loop([-0.2, -0.3], moved=0.013, moved_max=0.013))
    assert "not told apart by these starts" in small


def single(**kw):
    """A single run's metrics.json (the keys a loop round lacks included); ``kw`` as in :func:`metrics`."""
    base = dict(imag_horizon=15, replay_pusher_err_train_horizon=0.187, replay_pusher_err_eval_horizon=0.232,
                replay_block_err_train_horizon=0.19, replay_block_err_eval_horizon=0.25,
                zero_action_dream_final_tee_dist=0.061, train_clip_steps=16, dream_steps_per_train_clip=6.25)
    for d in OBS_NAMES:
        base[f"wm_one_step_ratio_{d}"], base[f"wm_open_loop_ratio_{d}"] = 1.4, 0.9
    base.update(kw)
    return metrics(**base)


def delta(runaway=True, **kw):
    """The delta model's metrics: beats copy-last one step ahead, its long dream runs away."""
    params = dict(dream=-0.643, se=0.035, dream_tr=-0.291, real_tr=-0.399, drift=0.021,
                  replay_pusher_err_train_horizon=0.296, replay_pusher_err_eval_horizon=4.97 if runaway else 0.15,
                  zero_action_dream_final_tee_dist=0.40,
                  **{f"wm_{kind}_ratio_{d}": r for d in OBS_NAMES for kind, r in (("one_step", 0.45),
                                                                                  ("open_loop", 0.53))})
    params.update(kw)
    return single(**params)


def ensemble(dis=0.036, **kw):
    """The ensemble's metrics: a rosier mean dream, members that disagree less than they err."""
    params = dict(dream=-0.126, se=0.020, dream_tr=-0.272, real_tr=-0.400, wm_ensemble_disagreement_train_horizon=dis,
                  wm_ensemble_disagreement_eval_horizon=dis * 1.2, replay_block_err_train_horizon=0.18,
                  replay_block_err_eval_horizon=0.198)
    params.update(kw)
    return single(**params)


def test_the_delta_sentence_reads_ratios_horizons_and_the_runaway():
    s = nb06.delta_sentence(single(), delta())
    assert "0.45/0.45 (x/y)" in s and "every one of the 6 observation dimensions (its largest ratio" in s and "1.40/1.40" in s
    assert "-0.243 ± 0.035 (gloomier than reality" in s and "+0.108" in s and "changed sign" in s
    assert "rosy over the span the actor trained on and gloomy" in s
    assert "moves a block nobody touches" in s and "4.970 m off after 10 s" in s and "left the table" in s
    assert "16-step clips" in s and "6.25" in s
    tame = nb06.delta_sentence(single(), delta(runaway=False, zero_action_dream_final_tee_dist=0.159))
    assert "left the table" not in tame and "nobody touches" not in tame and "no farther off" in tame
    assert "changed sign" not in nb06.delta_sentence(single(), delta(dream=-0.3))      # +0.100: rosy at both
    assert "gloomy over the span" in nb06.delta_sentence(single(), delta(dream_tr=-0.5, dream=-0.2))
    worse = delta()
    worse["wm_one_step_ratio_agent_x"] = 1.2
    assert "on 5 of 6 observation dimensions" in nb06.delta_sentence(single(), worse)


def test_the_ensemble_sentence_reads_gaps_and_shared_bias():
    s = nb06.ensemble_sentence(single(), ensemble(), penalty=1.0)
    assert "+0.274 ± 0.020" in s and "higher than the single model's, beyond the noise" in s
    assert "The ensemble with its penalty does not count as a fix" in s and "The expert control" in s
    assert "0.036 m" in s and "0.180 m" in s and "share" in s and "cannot see" in s
    assert "two different rollouts" in s and "evaluation dream" in s
    assert "penalty of 1 per metre" in s and "would cost 0.036 per step" in s and "not in these metrics" in s
    trained = nb06.ensemble_sentence(single(), ensemble(), penalty=1.0, train_disagreement=[0.05] * 30 + [0.03] * 20)
    assert "paid about 0.030 per step" in trained and "own training dreams" in trained
    assert "last 20 training iterations" in trained and "would cost" not in trained
    flagged = nb06.ensemble_sentence(single(), ensemble(dis=0.3))
    assert "may flag the error" in flagged and "cannot see" not in flagged and "penalty of" not in flagged
    same = nb06.ensemble_sentence(single(), ensemble(dream=-0.21, dream_tr=-0.28))
    assert "higher than" not in same and same.count("not told apart from the single model's") == 2
    assert "no ensemble disagreement" in nb06.ensemble_sentence(single(), single())


def test_the_conclusion_reads_each_fix():
    rounds = loop([-0.215, -0.387], training_tr=0.014, drift=-0.068, drift_se=0.029)
    c = nb06.conclusion(rounds, single(), delta(), ensemble())
    assert "real-data loop (1 round, 60 real policy episodes)" in c
    assert "its size fell from 0.185 to 0.013" in c and "changed sign beyond the noise" in c
    assert "its size rose from 0.185 to 0.274" in c
    assert c.count("does not count as a fix") == 3                    # the loop's training-horizon gap held
    assert "No fix produced a single real success" in c and "not beyond the noise and the minimum effect" in c
    # issue 38: a drift that went +0.230 -> -0.068 crossed zero: the opposite error, not a smaller one
    assert "the opposite error, not a smaller one" in c and "may have taught the model otherwise" not in c
    rounds = loop([-0.215, -0.387], drift=0.05, drift_se=0.01, zero_dream_block_moved_eval_horizon=0.05)
    rounds[0]["zero_dream_block_moved_eval_horizon"] = 0.2
    fell = nb06.conclusion(rounds, single(), delta(), ensemble())
    assert "it fell beyond the noise and the minimum effect, against round 0" in fell
    assert "may have taught the model otherwise: its zero-action dream now moves the untouched block 0.050 m" in fell
    # issue 38, seed 12: the drift's size fell, but the control moves the untouched block farther: no such lesson
    rounds[-1]["zero_dream_block_moved_eval_horizon"] = 0.26
    worse = nb06.conclusion(rounds, single(), delta(), ensemble())
    assert "The control says not" in worse and "may have taught" not in worse
    fixed = nb06.conclusion(loop([-0.215, -0.387], dream_tr=-0.395, training_tr=-0.05, training_tr_se=0.01),
                            single(), delta(), ensemble())
    assert "it counts as a fix of the gap" in fixed and "gloomier, not rosier" in fixed
    won = nb06.conclusion(loop([-0.215, -0.387], successes=[0, 2], training_tr=0.05, training_tr_se=0.01),
                          single(), delta(), ensemble())
    assert "the loop 2/30 against 0/30 for round 0" in won and "could be chance" in won and "No fix" not in won
    assert "keeps learning things only the model pays for" in won
    # issue 38's seed 12: 1/30 in every round, round 0 included, is not a success the loop bought
    same = nb06.conclusion(loop([-0.215, -0.387], successes=[1, 1]), single(), delta(), ensemble())
    assert "the loop 1/30, no more than round 0's 1/30: not something the fix bought" in same
    assert "appeared" not in same


def test_expert_ratios_are_read_from_either_kind_of_metrics():
    assert nb06.expert_ratio({"wm_one_step_ratio_tee_x": 0.4}, "one_step", "tee_x") == 0.4
    assert nb06.expert_ratio({"wm_expert_open_loop_ratio_tee_y": 0.7}, "open_loop", "tee_y") == 0.7
    with pytest.raises(KeyError):
        nb06.expert_ratio({}, "one_step", "tee_x")


# --- figures -------------------------------------------------------------------------------------
def test_every_figure_draws_with_labelled_axes():
    import matplotlib.pyplot as plt

    rounds = loop([-0.215, -0.214, -0.332, -0.387], touches=13, moved=0.05, moved_max=0.26, toward=-0.016)
    labelled(nb06.fig_rounds(rounds))
    labelled(nb06.fig_model_error(rounds))
    labelled(nb06.fig_block(rounds))
    labelled(nb06.fig_fixes(single(), rounds[-1], delta(), ensemble()))
    labelled(nb06.fig_fixes(single(), rounds[-1], delta(), ensemble(), labels=["a", "b", "c", "d"]))
    with pytest.raises(ValueError, match="labels"):
        nb06.fig_fixes(single(), rounds[-1], delta(), ensemble(), labels=["a"])
    zero = loop([-0.2, -0.3], errors=[model_errors(policy_copy_block=0.0)] * 2)   # a zero: no log axis
    assert nb06.fig_model_error(zero).axes[1].get_yscale() == "linear"
    plt.close("all")


# --- self-checks ---------------------------------------------------------------------------------
def test_self_checks_are_well_formed():
    assert 3 <= len(nb06.SELF_CHECKS) <= 4
    for name, q in nb06.SELF_CHECKS.items():
        assert isinstance(q, Question) and q.answer in q.options and len(q.options) >= 3, name
        assert q.why and "Type one of" in render(q, "")
        assert "is right" in render(q, q.answer)
    assert len({q.answer for q in nb06.SELF_CHECKS.values()}) > 1                # not always the same letter


# --- the yaw half, the expert control, the fix verdict, every seed --------------------------------
def test_the_halves_say_which_is_larger_only_beyond_the_noise_and_the_minimum_effect():
    m = metrics(yaw_frac=0.6)
    # |yaw| - |position| = 0.037: within k = 2.05 times its standard error, 0.021 (per start)
    close = nb06.halves_words(m)
    assert "neither half is clearly the larger" in close and "+0.037 ± 0.021" in close
    assert "the yaw half is the larger" in nb06.halves_words(metrics(yaw_frac=0.9))
    assert "the position half is the larger" in nb06.halves_words(metrics(yaw_frac=0.1))
    # beyond the noise (SEs of a thousandth) but 0.010 apart: below the minimum effect
    tiny = nb06.halves_words(metrics(dream=-0.3, se=0.0005, yaw_frac=0.55))
    assert "neither half is clearly the larger" in tiny
    opposite = nb06.halves_words(metrics(yaw_frac=1.5))                  # position half = -0.5 of the gap
    assert "partly cancel" in opposite and "the yaw half is the larger" in opposite
    cancel = nb06.halves_words(metrics(dream=-0.39, yaw_frac=10))         # +0.100 and -0.090: sum +0.010
    assert "cancel almost exactly" in cancel and "25%" in cancel and "0.190" in cancel
    assert "k = 2.05" in nb06.halves_rule(N) and "0.02." in nb06.halves_rule(N, short=True)
    assert nb06.yaw_share(m) == pytest.approx(0.6)
    assert math.isnan(nb06.yaw_share(metrics(dream=-0.4)))               # no gap, no share


def test_the_expert_control_has_three_verdicts():
    assert "recognises success" in nb06.expert_words(metrics(expert_dream=0.07, expert_dream_se=0.019))[1]
    invalid = nb06.expert_words(metrics(expert_dream=0.07, zero_dream_block_moved_eval_horizon=0.3))[1]
    assert "not valid on this run" in invalid and "the dream recognises success:" not in invalid
    assert "less than standing still" in nb06.expert_words(metrics())[1]
    tiny = nb06.expert_words(metrics(expert_dream=0.015, expert_dream_se=0.001))[1]     # beyond noise, too small
    assert "does not tell" in tiny and "minimum effect" in tiny
    nums = nb06.expert_words(metrics())[0]
    assert "dream -0.065 ± 0.019" in nums and "reality +0.168 ± 0.014" in nums


def test_the_rounds_sentence_reads_halves_and_the_expert_per_round():
    rounds = loop([-0.215, -0.214, -0.332, -0.387])
    for m, e in zip(rounds, (-0.065, 0.003, 0.011, 0.071)):
        m["expert_signal_dream_eval_horizon"] = e
    s = nb06.rounds_sentence(rounds)
    assert "A half counts as the larger only when" in s and "start by start" in s
    assert "round 0: -0.065 ± 0.019 (pays them less than standing still)" in s
    assert "round 1: +0.003 ± 0.019 (does not tell them from standing still)" in s
    assert "round 3: +0.071 ± 0.019 (pays them more than standing still)" in s
    assert "+0.168 ± 0.014 in every round" in s and "30/30" in s
    assert "the loop taught the model to pay the expert's pushes more" in s and "against round 0" in s
    # the path, not only the end points: -0.065 -> +0.003 -> +0.011 -> +0.071 went one way
    assert "0 -> 1: +0.068; 1 -> 2: +0.008; 2 -> 3: +0.060" in s and "the path turns" not in s
    flat = nb06.rounds_sentence(loop([-0.215, -0.387]))
    assert "did not change what the model pays" in flat
    # issue 38's path -0.080, +0.065, +0.063, -0.018 is told as a path that turns
    turning = loop([-0.215, -0.214, -0.332, -0.387])
    for m, e in zip(turning, (-0.065, -0.145, -0.080, -0.017)):
        m["expert_signal_dream_eval_horizon"] = e
    assert "the path turns" in nb06.rounds_sentence(turning)
    # a control that moves the untouched block is not read as teaching: the expert's own gap is read instead
    for m in turning:
        m["zero_dream_block_moved_eval_horizon"] = 0.3
    bad = nb06.rounds_sentence(turning)
    assert "control invalid" in bad and "cannot be read as the loop teaching" in bad and "expert's own gap" in bad
    assert "taught the model" not in bad

    def halves(*pairs):
        rs = loop([-0.215] * len(pairs))
        for m, (p, y) in zip(rs, pairs):
            m.update(imagination_gap_position_eval_horizon=p, imagination_gap_yaw_eval_horizon=y,
                     imagination_gap_se_position_eval_horizon=0.01, imagination_gap_se_yaw_eval_horizon=0.01)
        return nb06.rounds_sentence(rs)

    yaw, pos, neither = (0.05, 0.15), (0.15, 0.05), (0.11, 0.115)
    assert "in every round, the block's angle, not its distance, is clearly the larger" in halves(yaw, yaw, yaw)
    assert "the block's distance to the target is clearly the larger part" in halves(pos, pos)
    assert "in no round is either half clearly the larger" in halves(neither, neither)
    mixed = halves(yaw, pos, neither)
    assert "changes from round to round: yaw in round 0, position in round 1, neither clearly in round 2" in mixed
    part = halves(yaw, yaw, neither)
    assert "the yaw half is clearly the larger in rounds 0, 1, and neither half is clearly the larger in round 2" \
        in part and "changes from round to round" not in part
    t = nb06.rounds_table(rounds)
    assert "+0.074 ± 0.014 / +0.111 ± 0.016" in t and "+0.071 ± 0.019 | +0.168 ± 0.014 |" in t


def test_a_fix_needs_both_horizons_no_sign_flip_and_a_dream_on_the_table():
    ref = single()
    good = single(dream=-0.39, dream_tr=-0.395)                          # both gaps near zero, same sign
    ok, text = nb06.fix_verdict(ref, good, "X", "the state model")
    assert ok and "X counts as a fix" in text and "within the 0.5 m" in text
    off = single(dream=-0.39, dream_tr=-0.395, zero_action_dream_final_tee_dist=0.80,
                 zero_dream_block_moved_eval_horizon=0.64)
    ok, text = nb06.fix_verdict(ref, off, "X", "the state model")
    assert not ok and "farther than the 0.5 m" in text
    # issue 38's seed 12: the untouched block carried away 0.26 m, on the table, yet no fix: the reference's
    # dream moved it 0.01 m
    away = single(dream=-0.39, dream_tr=-0.395, zero_dream_block_moved_eval_horizon=0.26)
    ok, text = nb06.fix_verdict(ref, away, "X", "the state model")
    assert not ok and "moves the untouched block 0.260 m" in text and "within the 0.5 m" in text
    # the drift turned into the opposite error: the gap closed by that trade
    traded = single(dream=-0.39, dream_tr=-0.395, drift=-0.2)
    ok, text = nb06.fix_verdict(ref, traded, "X", "the state model")
    assert not ok and "changed sign beyond the noise, the opposite error" in text
    one = single(dream=-0.39)                                            # training horizon unchanged
    ok, text = nb06.fix_verdict(ref, one, "X", "the state model")
    assert not ok and "its size did not fall beyond the noise" in text
    flip = single(dream=-0.60, dream_tr=-0.395)                          # +0.185 -> -0.200: opposite error
    ok, text = nb06.fix_verdict(ref, flip, "X", "the state model")
    assert not ok and "changed sign beyond the noise" in text
    # the gap reaches zero only because its halves cancel: +0.100 yaw, -0.090 position
    cancel = single(dream=-0.39, dream_tr=-0.395, yaw_frac=10)
    ok, text = nb06.fix_verdict(ref, cancel, "X", "the state model")
    assert not ok and "over all 100 steps 0.185 -> 0.190 (did not fall" in text
    assert "cancelling halves is not a fix" in text
    ok, text = nb06.fix_verdict(ref, good, "X", "the state model")
    assert "over all 100 steps 0.185 -> 0.010 (fell beyond the noise and the minimum effect: k = 2.05" in text


def test_the_delta_sentence_flags_a_runaway_untouched_block():
    s = nb06.delta_sentence(single(), delta(zero_action_dream_final_tee_dist=0.80))
    assert "farther from the target than the walls are (0.5 m)" in s and "does not count as a fix" in s
    s = nb06.delta_sentence(single(), delta())
    assert "farther from the target than the walls" not in s and "The expert control" in s
    assert "from the block's position" in s


def test_the_fixes_table_has_a_row_per_run():
    rounds = loop([-0.215, -0.387])
    t = nb06.fixes_table(single(), rounds[-1], delta(), ensemble())
    rows = [ln for ln in t.splitlines() if ln.startswith("| ") and not ln.startswith("| run")]
    assert len(rows) == 4 and rows[1].startswith("| loop, after round 1")
    assert "| 60% (neither half clearly larger) |" in rows[0] and "| 0.400 |" in rows[2] and "-0.065 ± 0.019" in rows[3]


def test_the_summary_table_reads_every_seed_it_finds(tmp_path):
    import json

    assert "No metrics found" in nb06.summary_table(tmp_path)
    (tmp_path / "metrics" / "closing" / "loop_seed0").mkdir(parents=True)
    (tmp_path / "metrics" / "closing" / "loop_seed0" / "loop.json").write_text(
        json.dumps(loop([-0.215, -0.214, -0.387])))
    (tmp_path / "metrics" / "closing" / "delta_seed0.json").write_text(json.dumps(delta()))
    (tmp_path / "metrics" / "closing" / "ensemble_seed0.json").write_text(json.dumps(ensemble()))
    (tmp_path / "metrics" / "seed3.json").write_text(json.dumps(single(dream=-0.3)))
    (tmp_path / "metrics" / "seed3_notes.json").write_text("{}")               # not a seed's metrics
    runs = nb06.summary_runs(tmp_path)
    assert list(runs) == [0, 3] and set(runs[0]) == {"offline", "loop", "delta", "ensemble"}
    assert set(runs[3]) == {"offline"} and runs[0]["loop"]["round"] == 2
    t = nb06.summary_table(tmp_path)
    assert "Seeds found under" in t and "0, 3 (2 seeds)" in t
    rows = [ln for ln in t.splitlines() if ln.startswith("| ") and not ln.startswith("| seed")]
    assert len(rows) == 5 and rows[0].startswith("| 0 | offline") and rows[4].startswith("| 3 | offline")
    assert "+0.185 ± 0.020" in rows[0] and "| 2 |" in rows[1] and "| 0/30 |" in rows[0]
    assert "seed 3: loop, last round" in t and "seed 3: delta model" in t


def test_every_sentence_decision_is_a_registered_claim():
    from pusht.nb import claims

    claims.LEDGER.clear()
    rounds = loop([-0.215, -0.214, -0.332, -0.387], touches=13, moved=0.05, moved_max=0.26, toward=-0.016)
    nb06.reconcile_text(rounds)
    nb06.rounds_sentence(rounds)
    nb06.model_error_sentence(rounds)
    nb06.block_sentence(rounds)
    nb06.delta_sentence(single(), delta())
    nb06.ensemble_sentence(single(), ensemble(), penalty=1.0)
    nb06.conclusion(rounds, single(), delta(), ensemble())
    seen = {r["claim"] for r in claims.LEDGER}
    mine = {name for name in claims.REGISTRY if name.startswith("06.")}
    assert seen <= mine and len(mine) >= 20
    # every predicate gives the recorded outcome again on its recorded inputs
    for r in claims.LEDGER:
        assert claims.REGISTRY[r["claim"]].predicate(**r["inputs"]) == r["holds"], r["claim"]
    # nothing registered for notebook 06 is fixed text
    assert not any(claims.REGISTRY[n].fixed for n in mine)


def test_every_claim_takes_both_branches_somewhere():
    from pusht.nb import claims

    claims.LEDGER.clear()
    cases = [loop([-0.215, -0.214, -0.332, -0.387], touches=13, moved=0.05, moved_max=0.26, toward=-0.016),
             loop([-0.215, -0.100], successes=[0, 1], touches=2, moved=0.05, moved_max=0.06, toward=0.045),
             loop([-0.215, -0.450], successes=[0, 9], touches=25, yaw_frac=0.1),
             loop([-0.215, -0.450], yaw_frac=0.9),
             loop([-0.215, -0.400, -0.300, -0.250], reals=[-0.4, -0.25, -0.3, -0.3], expert_dream=0.07,
                  training_tr=0.05, training_tr_se=0.01),
             loop([-0.215, -0.387], dream_tr=-0.395, training_tr=-0.05, training_tr_se=0.01, moved=0.0,
                  moved_max=0.0, toward=0.0, drift=0.0),
             # the control invalid, the expert's own gap above and below reality; the drift's size grows
             loop([-0.215, -0.387], zero_dream_block_moved_eval_horizon=0.3, expert_gap_eval_horizon=0.1,
                  drift=0.5),
             loop([-0.215, -0.387], zero_dream_block_moved_eval_horizon=0.3, expert_gap_eval_horizon=0.001)]
    errs = [model_errors(b, 0.1 / (r + 1), expert_block=0.01 + 0.002 * r) for r, b in enumerate((0.064, 0.015))]
    cases.append(loop([-0.2, -0.3], errors=errs, moved=0.05, moved_max=0.06, toward=-0.04))
    better = [model_errors(0.064 / (r + 1), 0.117 / (r + 1), ol_policy=(0.13 / (r + 1), 0.14 / (r + 1)))
              for r in range(3)]
    cases.append(loop([-0.2, -0.3, -0.35], errors=better))
    cases.append(loop([-0.215, -0.273]))        # a drop of 0.058, about k = 2.05 standard errors: a thin margin
    cases.append(loop([-0.215, -0.380, -0.400], reals=[-0.400, -0.425, -0.440]))   # reality below doing nothing
    for rounds in cases:
        nb06.ex3_verdict(rounds)
        nb06.ex3_reconciliation(rounds)
        nb06.reconcile_text(rounds)
        nb06.rounds_sentence(rounds)
        nb06.model_error_sentence(rounds)
        nb06.block_sentence(rounds)
        nb06.conclusion(rounds, single(), delta(), ensemble())
    worse = delta(zero_action_dream_final_tee_dist=0.8, replay_pusher_err_eval_horizon=0.1, drift=-0.2)
    worse["wm_one_step_ratio_agent_x"] = 1.2
    for d in (delta(), worse, delta(runaway=False, zero_action_dream_final_tee_dist=0.159),
              single(dream=-0.39, dream_tr=-0.395), single(dream=-0.39, dream_tr=-0.395, yaw_frac=10)):
        nb06.delta_sentence(single(), d)
    for e in (ensemble(), ensemble(dis=0.3), ensemble(dream=-0.5, dream_tr=-0.45, expert_dream=0.015,
                                                      expert_dream_se=0.001)):
        nb06.ensemble_sentence(single(), e, penalty=1.0)
    outcomes: dict = {}
    for r in claims.LEDGER:
        outcomes.setdefault(r["claim"], set()).add(r["holds"])
    mine = {name for name in claims.REGISTRY if name.startswith("06.")}
    assert set(outcomes) == mine, mine - set(outcomes)
    one_sided = {n for n, o in outcomes.items() if o != {True, False}}
    assert not one_sided, one_sided


def test_the_dream_coming_down_is_read_against_the_dream_of_a_pusher_that_never_moves():
    # issue 38, seeds 11 and 12: the policy's dream came down, but the zero-action dream came down more
    rounds = loop([-0.215, -0.387])
    rounds[-1]["zero_action_dream_return_per_step"] = rounds[0]["zero_action_dream_return_per_step"] - 0.25
    s = nb06.reconcile_text(rounds)
    assert "The dream came down to meet reality" in s and "The whole dream grew gloomier" in s
    assert "stopped promising" not in s
    rounds[-1]["zero_action_dream_return_per_step"] = rounds[0]["zero_action_dream_return_per_step"]
    s = nb06.reconcile_text(rounds)
    assert "stopped promising what this policy does not deliver" in s and "-0.172 beyond the control's change" in s


def test_a_gap_that_shrank_by_the_drift_turning_over_is_said_to_have():
    # issue 38, seeds 11 and 12: the gap shrank because the drift went +0.16 -> -0.06, through zero
    rounds = loop([-0.215, -0.387], drift=-0.064, drift_se=0.024)
    s = nb06.reconcile_text(rounds)
    assert "The gap shrank" in s and "through zero beyond the noise" in s and "trading its error" in s
    assert "through zero" not in nb06.reconcile_text(loop([-0.215, -0.387], drift=0.05, drift_se=0.01))
    # reality judged against its own noise: a fall of 0.031 with per-start SEs of 0.003 moved
    rounds = loop([-0.215, -0.215], reals=[-0.400, -0.431])
    assert nb06.sides(rounds[0], rounds[-1])["moved"]["real"] == "down"
