#!/usr/bin/env python3
"""The enavi Python environment: an episode to its end with random masked actions, the same seed
giving the same observations, bad actions refused, and the vectorised form."""

import unittest

import numpy as np

import enavi


def run_episode(env, seed, action_seed=0):
    rng = np.random.default_rng(action_seed)
    obs, info = env.reset(seed=seed)
    observations, rewards = [obs], []
    while True:
        action = rng.choice(np.flatnonzero(info["action_mask"]))
        obs, reward, terminated, truncated, info = env.step(action)
        observations.append(obs)
        rewards.append(reward)
        if terminated or truncated:
            return np.array(observations), np.array(rewards), terminated, truncated, info


class EnvTest(unittest.TestCase):
    def test_sizes(self):
        env = enavi.make("empty", board="tx2")
        self.assertEqual(env.observation_size, 16)
        self.assertEqual(env.action_size, 98)
        obs, info = env.reset(seed=1)
        self.assertEqual(obs.shape, (16,))
        self.assertEqual(obs.dtype, np.float64)
        self.assertEqual(info["action_mask"].shape, (98,))
        self.assertGreater(info["action_mask"].sum(), 0)

    def test_episode_runs_to_its_end_with_random_masked_actions(self):
        env = enavi.make("empty", board="tx2")
        obs, rewards, terminated, truncated, info = run_episode(env, seed=2)
        self.assertTrue(terminated or truncated)
        self.assertGreater(len(rewards), 10)
        self.assertTrue(np.isfinite(obs).all() and np.isfinite(rewards).all())
        self.assertIn(info["end_reason"], ("goal_reached", "collision", "timeout", "failsafe"))
        self.assertEqual(terminated, info["end_reason"] in ("goal_reached", "collision"))

    def test_same_seed_same_observations(self):
        env = enavi.make("s1", board="pi4b")
        a = run_episode(env, seed=5)
        b = run_episode(env, seed=5)
        np.testing.assert_array_equal(a[0], b[0])
        np.testing.assert_array_equal(a[1], b[1])
        # A reset in the middle of an episode abandons it cleanly.
        env.reset(seed=5)
        c = run_episode(env, seed=5)
        np.testing.assert_array_equal(a[0], c[0])

    def test_infeasible_action_and_step_without_reset_are_refused(self):
        env = enavi.make("empty")
        with self.assertRaises(Exception):
            env.step(0)
        _, info = env.reset(seed=1)
        blocked = np.flatnonzero(info["action_mask"] == 0)
        if blocked.size:
            with self.assertRaises(ValueError):
                env.step(int(blocked[0]))
        with self.assertRaises(ValueError):
            env.step(10_000)

    def test_bad_input(self):
        with self.assertRaises(ValueError):
            enavi.make("empty", board="no-such-board")
        with self.assertRaises(ValueError):
            enavi.make("empty", clock="emulated")

    def test_vector_env_steps_n_processes(self):
        venv = enavi.make_vec(2, world="empty", board="tx2")
        try:
            obs, info = venv.reset(seed=3)
            self.assertEqual(obs.shape, (2, 16))
            self.assertEqual(info["action_mask"].shape, (2, 98))
            rng = np.random.default_rng(1)
            for _ in range(20):
                actions = [rng.choice(np.flatnonzero(m)) for m in info["action_mask"]]
                obs, reward, terminated, truncated, info = venv.step(actions)
                self.assertEqual(obs.shape, (2, 16))
                self.assertEqual(reward.shape, (2,))
            # Environment 0 with seed 3 matches a single environment with seed 3.
            single = enavi.make("empty", board="tx2")
            o, _ = single.reset(seed=3)
            venv_obs, _ = venv.reset(seed=3)
            np.testing.assert_array_equal(o, venv_obs[0])
        finally:
            venv.close()


if __name__ == "__main__":
    unittest.main()
