#!/usr/bin/env python3
"""Learned-navigation environment throughput (docs/rl.md, "Benchmark: the navigation environment"):
env steps per CPU second of one core at two image sizes, one environment in this process, random
actions, resets included (a reset generates and prepares a new forest); the same with the image
at 64x48 in a VectorEnv of one process per core (wall rate over all of them). Reported beside the
real-time factor (sim seconds per CPU second) and as ratios to the 64x48 run of this process.

    PYTHONPATH=build/python /usr/bin/python3 bench/rl/nav_env_bench.py [--steps 3000]
"""

import argparse
import os
import time

import numpy as np

import enavi

WORLD_PARAMS = {"density": "2", "length": "20"}


def run(image, steps, latency="board"):
    env = enavi.make_nav("forest", board="pi4b", image=image, latency=latency, world_params=WORLD_PARAMS)
    rng = np.random.default_rng(0)
    sim_s, seed, done = 0.0, 1, True
    cpu0 = time.process_time()
    for _ in range(steps):
        if done:
            env.reset(seed=seed)
            seed += 1
            t_prev = 0.0
        obs, reward, terminated, truncated, info = env.step(rng.uniform(-0.2, 1.0, size=4) * [1, 0.3, 0.2, 0.3])
        done = terminated or truncated
        sim_s += info["t"] - t_prev
        t_prev = info["t"]
    cpu = time.process_time() - cpu0
    return steps / cpu, sim_s / cpu, seed - 1


def run_vector(n, steps):
    envs = enavi.make_nav_vec(n, world="forest", board="pi4b", world_params=WORLD_PARAMS)
    envs.reset(seed=1)
    rng = np.random.default_rng(0)
    wall0 = time.perf_counter()
    for _ in range(steps // n):
        envs.step(rng.uniform(-0.2, 1.0, size=(n, 4)) * [1, 0.3, 0.2, 0.3])
    rate = (steps // n) * n / (time.perf_counter() - wall0)
    envs.close()
    return rate


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=3000)
    args = parser.parse_args()
    print("%-22s %14s %12s %9s %s" % ("run", "env steps/s", "sim s / s", "ratio", "episodes"))
    ref = None
    for image in ((64, 48), (160, 120)):
        rate, rtf, episodes = run(image, args.steps)
        ref = ref or rate
        print("%-22s %14.0f %12.1f %9.3f %d" % ("%dx%d, 1 core" % image, rate, rtf, rate / ref, episodes))
    cores = os.cpu_count() or 1
    rate = run_vector(cores, args.steps)
    print("%-22s %14.0f %12s %9.3f" % ("64x48, %d processes" % cores, rate, "(wall)", rate / ref))
    print("gym-pybullet-drones (published): one drone, 64x48 depth with OpenGL, 10.8x real time")


if __name__ == "__main__":
    main()
