#!/usr/bin/env python3
"""enavi's learned-navigation environment (enavi.make_nav): image observations at two sizes, the
same seed and actions giving the same episode, the board's latency in the loop, bad input refused,
the vectorised form; and the PyTorch example's policy file flying in `enavi fly` (argv[1]: the CLI).
"""

import json
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np

import enavi

FOREST = {"density": "2", "length": "20"}
EXAMPLES = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "examples")
CLI = sys.argv.pop(1) if len(sys.argv) > 1 else None


def fly(env, seed, steps=60, action_seed=0):
    """`steps` random actions (or to the end): observations and rewards."""
    rng = np.random.default_rng(action_seed)
    obs, _ = env.reset(seed=seed)
    depths, states, rewards = [obs["depth"]], [obs["state"]], []
    for _ in range(steps):
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-0.3, 1.0, size=4) * [1, 0.3, 0.2, 0.3])
        depths.append(obs["depth"])
        states.append(obs["state"])
        rewards.append(reward)
        if terminated or truncated:
            break
    return np.array(depths), np.array(states), np.array(rewards)


class NavEnvTest(unittest.TestCase):
    def test_images_at_two_sizes_with_the_state_and_goal(self):
        for image in ((64, 48), (160, 120)):
            env = enavi.make_nav("forest", board="pi4b", image=image, world_params=FOREST)
            obs, info = env.reset(seed=3)
            self.assertEqual(obs["depth"].shape, (image[1], image[0]))
            self.assertEqual(obs["depth"].dtype, np.float32)
            self.assertTrue(((obs["depth"] >= 0) & (obs["depth"] <= 1)).all())
            self.assertLess(obs["depth"].min(), 1.0, "trees in view")
            self.assertEqual(obs["state"].shape, (8,))
            np.testing.assert_allclose(obs["state"][:3], [1, 0, 0], atol=1e-6, err_msg="the goal straight ahead")
            self.assertEqual(info["t"], 0.0)

    def test_the_same_seed_and_actions_give_the_same_episode(self):
        a = fly(enavi.make_nav("forest", world_params=FOREST), seed=5)
        b = fly(enavi.make_nav("forest", world_params=FOREST), seed=5)
        for x, y in zip(a, b):
            np.testing.assert_array_equal(x, y)
        c = fly(enavi.make_nav("forest", world_params=FOREST), seed=6)
        self.assertFalse(np.array_equal(a[0][0], c[0][0]), "another seed, another forest")

    def test_the_boards_latency_is_in_the_loop(self):
        # The same actions land ~1 ms later on pi4b than without a board: the flights part.
        board = fly(enavi.make_nav("forest", latency="board", world_params=FOREST), seed=5)
        none = fly(enavi.make_nav("forest", latency="none", world_params=FOREST), seed=5)
        np.testing.assert_array_equal(board[0][0], none[0][0])
        self.assertFalse(np.array_equal(board[1][-1], none[1][-1]))
        self.assertLess(np.abs(board[1][-1] - none[1][-1]).max(), 0.2, "by a little")

    def test_flying_forward_reaches_the_goal_or_ends_with_a_reason(self):
        env = enavi.make_nav("forest", world_params=FOREST)
        env.reset(seed=1)
        total = 0.0
        while True:
            obs, reward, terminated, truncated, info = env.step([1, 0, 0, 0])
            total += reward
            if terminated or truncated:
                break
        self.assertIn(info["end_reason"], ("goal_reached", "collision"))
        if info["end_reason"] == "goal_reached":
            self.assertGreater(total, 19 + 10 - 1, "progress along the course plus the goal's reward")
        self.assertGreater(info["flight_time_s"], 1)
        with self.assertRaises(RuntimeError):
            env.step([1, 0, 0, 0])

    def test_bad_input_is_refused_by_name(self):
        with self.assertRaisesRegex(ValueError, "image"):
            enavi.make_nav("forest", image=(63, 48))
        with self.assertRaisesRegex(ValueError, "latency"):
            enavi.make_nav("forest", latency="some")
        with self.assertRaisesRegex(ValueError, "board"):
            enavi.make_nav("forest", board="commodore64")
        with self.assertRaisesRegex(ValueError, "learned.zero_latency"):
            enavi.make_nav("forest", overrides={"learned.zero_latency": 1})
        env = enavi.make_nav("forest", world_params=FOREST)
        env.reset(seed=1)
        with self.assertRaisesRegex(ValueError, "expected 4 values"):
            env.step([1, 0])
        with self.assertRaisesRegex(ValueError, "finite"):
            env.step([np.nan, 0, 0, 0])
        env.step([0, 0, 0, 0])  # the decision is still open after a refused action

    def test_vector_env_stacks_images_and_resets_itself(self):
        envs = enavi.make_nav_vec(2, world="forest", world_params=FOREST, timeout_s=1.0)
        obs, info = envs.reset(seed=1)
        self.assertEqual(obs["depth"].shape, (2, 48, 64))
        self.assertEqual(obs["state"].shape, (2, 8))
        ended = False
        for _ in range(40):
            obs, reward, terminated, truncated, info = envs.step(np.zeros((2, 4)))
            if truncated.any():
                ended = True
                i = int(np.flatnonzero(truncated)[0])
                self.assertEqual(info["final_observation"][i]["depth"].shape, (48, 64))
                self.assertEqual(info["final_info"][i]["end_reason"], "timeout")
                break
        envs.close()
        self.assertTrue(ended, "hovering for 1 s times out")


@unittest.skipIf(CLI is None, "needs the enavi CLI's path")
class TorchExampleTest(unittest.TestCase):
    def test_the_examples_policy_file_is_the_torch_network_and_flies(self):
        try:
            import torch
        except ImportError:
            self.skipTest("python3-torch is not installed")
        sys.path.insert(0, EXAMPLES)
        import torch_nav_ppo
        with tempfile.TemporaryDirectory() as tmp:
            # A few PPO iterations through the example itself: it writes a file and a curve.
            out = os.path.join(tmp, "nav.json")
            subprocess.run([sys.executable, os.path.join(EXAMPLES, "torch_nav_ppo.py"), "--out", out,
                            "--steps", "256", "--batch", "128"], check=True, env=os.environ)
            with open(os.path.join(tmp, "nav.csv")) as f:
                self.assertEqual(len(f.read().splitlines()), 3, "header and two iterations")
            with open(out) as f:
                self.assertEqual(len(json.load(f)["log_std"]), 4, "the Gaussian a sampling collection draws from")
            # The file holds the torch network: the same action on the same observation.
            torch.manual_seed(7)
            actor = torch_nav_ppo.Actor(64, 48)
            path = os.path.join(tmp, "actor.json")
            torch_nav_ppo.save_policy(actor, 64, 48, path, {})
            rng = np.random.default_rng(1)
            depth = rng.random((48, 64)).astype(np.float32)
            state = rng.normal(size=8).astype(np.float32)
            with torch.no_grad():
                ref = actor(torch.as_tensor(depth[None]), torch.as_tensor(state[None]))[0].double().numpy()
            np.testing.assert_allclose(enavi.nav_policy_forward(path, depth, state.astype(np.float64)), ref, atol=1e-6)
            # The trained file flies as a method on pi4b.
            run = subprocess.run([CLI, "fly", "--method", "learned", "--policy", out, "--board", "pi4b",
                                  "--world", "forest", "--param", "density=2", "--param", "length=20",
                                  "--seed", "1", "--json"], check=True, capture_output=True, text=True)
            result = json.loads(run.stdout)
            self.assertEqual(result["method"], "learned")
            self.assertGreater(result["task_cpu_util_pct"]["inference"], 0)
            self.assertEqual(result["notes"]["depth_stream"], "64x48")


if __name__ == "__main__":
    unittest.main()
