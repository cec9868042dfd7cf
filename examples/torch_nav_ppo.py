#!/usr/bin/env python3
"""PPO with PyTorch on enavi's learned-navigation environment (enavi.make_nav): a small CNN policy
(the architecture of rl::MakeNavPolicy: three convolutions, one hidden layer of 64, a tanh mean
and a learned log standard deviation), clipped surrogate objective, GAE. Writes the policy as a
nav policy file that `enavi fly --method learned --policy FILE` flies, and the learning curve
(one row per iteration) as CSV.

    PYTHONPATH=build/python /usr/bin/python3 examples/torch_nav_ppo.py --out nav.json \
        [--board pi4b] [--latency board|none] [--minutes 40] [--steps N] [--envs 1]

Debian's python3-torch and numpy: run it with /usr/bin/python3.
"""

import argparse
import base64
import csv
import hashlib
import json
import os
import struct
import time

import numpy as np
import torch
from torch import nn

import enavi

# A sparse forest (docs/rl.md): 2 trees per 100 m^2 (the generator's default is 3) on a 20 m course.
WORLD, WORLD_PARAMS = "forest", {"density": "2", "length": "20"}
LAYOUT = ("per convolution the weights (out x in x kernel x kernel) then the bias, then per linear layer "
          "the weights (out x in, row-major) then the bias: PyTorch's Conv2d and Linear")
CONV = [(8, 5, 2), (16, 3, 2), (16, 3, 2)]
HIDDEN = 64
ACTION_SCALE = [2.0, 2.0, 1.0, 1.0]


def conv_trunk():
    layers, channels = [], 1
    for out, kernel, stride in CONV:
        layers += [nn.Conv2d(channels, out, kernel, stride), nn.ReLU()]
        channels = out
    return nn.Sequential(*layers, nn.Flatten())


class Actor(nn.Module):
    """What the nav policy file holds: image features and the state through a tanh layer to a
    tanh mean."""

    def __init__(self, width, height):
        super().__init__()
        self.conv = conv_trunk()
        with torch.no_grad():
            flat = self.conv(torch.zeros(1, 1, height, width)).shape[1]
        self.fc = nn.Sequential(nn.Linear(flat + 8, HIDDEN), nn.Tanh(), nn.Linear(HIDDEN, 4), nn.Tanh())

    def forward(self, depth, state):
        return self.fc(torch.cat([self.conv(depth.unsqueeze(1)), state], dim=1))


class Critic(nn.Module):
    def __init__(self, width, height):
        super().__init__()
        self.conv = conv_trunk()
        with torch.no_grad():
            flat = self.conv(torch.zeros(1, 1, height, width)).shape[1]
        self.fc = nn.Sequential(nn.Linear(flat + 8, HIDDEN), nn.Tanh(), nn.Linear(HIDDEN, 1))

    def forward(self, depth, state):
        return self.fc(torch.cat([self.conv(depth.unsqueeze(1)), state], dim=1)).squeeze(-1)


def save_policy(actor, width, height, path, metadata, log_std=None):
    """The actor as an enavi nav policy file (navstack/rl/nav_policy.h): float32 little-endian
    weights in base64 with their sha256, and the exploration Gaussian's log_std (a farm collection
    job with `sample: true` draws from it)."""
    values = []
    for module in list(actor.conv) + list(actor.fc):
        if isinstance(module, (nn.Conv2d, nn.Linear)):
            values += module.weight.detach().double().flatten().tolist()
            values += module.bias.detach().double().flatten().tolist()
    raw = struct.pack("<%df" % len(values), *values)
    doc = {"format": "enavi-nav-policy", "version": 1,
           "input": {"width": width, "height": height, "max_depth_m": 10.0},
           "conv": [{"out": o, "kernel": k, "stride": s} for o, k, s in CONV],
           "hidden": [HIDDEN], "action_scale": ACTION_SCALE,
           "parameters": {"dtype": "float32", "byte_order": "little", "encoding": "base64", "layout": LAYOUT,
                          "count": len(values), "sha256": hashlib.sha256(raw).hexdigest(),
                          "data": base64.b64encode(raw).decode()},
           "metadata": metadata}
    if log_std is not None:
        doc["log_std"] = [float(v) for v in log_std.detach().double().tolist()]
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(doc, f, separators=(",", ":"))
        f.write("\n")
    os.replace(tmp, path)


def to_tensors(obs):
    return (torch.as_tensor(obs["depth"], dtype=torch.float32), torch.as_tensor(obs["state"], dtype=torch.float32))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, help="the nav policy file to write")
    parser.add_argument("--curve", help="learning curve CSV (default: OUT with .csv)")
    parser.add_argument("--board", default="pi4b")
    parser.add_argument("--latency", choices=("board", "none"), default="board")
    parser.add_argument("--image", default="64x48", help="WIDTHxHEIGHT, a decimation of 640x480")
    parser.add_argument("--minutes", type=float, default=40.0, help="wall-clock budget of the training")
    parser.add_argument("--steps", type=int, default=0, help="environment steps (0: until --minutes)")
    parser.add_argument("--envs", type=int, default=1, help="environment processes")
    parser.add_argument("--batch", type=int, default=1024, help="environment steps per update")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    width, height = (int(v) for v in args.image.split("x"))
    torch.manual_seed(args.seed)
    torch.set_num_threads(1)
    curve_path = args.curve or os.path.splitext(args.out)[0] + ".csv"

    envs = enavi.make_nav_vec(args.envs, world=WORLD, board=args.board, image=(width, height),
                              latency=args.latency, world_params=WORLD_PARAMS)
    actor, critic = Actor(width, height), Critic(width, height)
    log_std = nn.Parameter(torch.full((4,), -0.5))
    opt = torch.optim.Adam(list(actor.parameters()) + list(critic.parameters()) + [log_std], lr=3e-4)
    gamma, lam, clip, epochs, minibatch = 0.99, 0.95, 0.2, 4, 256

    # Training worlds are seeds 1000+ (evaluation flies seeds 1..N): reset i starts at seed + i.
    obs, _ = envs.reset(seed=1000 * args.seed)
    start, steps, iteration = time.time(), 0, 0
    episode_returns = np.zeros(args.envs)
    finished = []  # (return, success, collided, flight time) of episodes since the last row
    with open(curve_path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["iteration", "env_steps", "wall_s", "episodes", "mean_return", "success_rate",
                         "collision_rate", "mean_flight_time_s"])
        while True:
            if args.steps and steps >= args.steps:
                break
            if not args.steps and time.time() - start > 60 * args.minutes:
                break
            buf = {k: [] for k in ("depth", "state", "action", "logp", "value", "reward", "done")}
            for _ in range(args.batch // args.envs):
                depth, state = to_tensors(obs)
                with torch.no_grad():
                    mean = actor(depth, state)
                    dist = torch.distributions.Normal(mean, log_std.exp())
                    action = dist.sample()
                    value = critic(depth, state)
                obs, reward, terminated, truncated, info = envs.step(action.numpy())
                done = np.logical_or(terminated, truncated)
                for k, x in zip(buf, (depth, state, action, dist.log_prob(action).sum(-1), value,
                                      torch.as_tensor(reward, dtype=torch.float32),
                                      torch.as_tensor(terminated, dtype=torch.float32))):
                    buf[k].append(x)
                episode_returns += reward
                for i in np.flatnonzero(done):
                    fi = info["final_info"][i]
                    finished.append((episode_returns[i], fi.get("success", 0.0), fi.get("collided", 0.0),
                                     fi.get("flight_time_s", float("nan"))))
                    episode_returns[i] = 0.0
                # A truncated episode is not a terminal state: its value carries on (bootstrapped
                # below from the critic's value of the final observation).
                for i in np.flatnonzero(np.logical_and(truncated, ~terminated)):
                    fo = info["final_observation"][i]
                    with torch.no_grad():
                        v = critic(torch.as_tensor(fo["depth"][None]), torch.as_tensor(fo["state"][None]))
                    buf["reward"][-1][i] += gamma * float(v)
                    buf["done"][-1][i] = 1.0
                steps += args.envs
            with torch.no_grad():
                last_value = critic(*to_tensors(obs))
            rewards, values, dones = (torch.stack(buf[k]) for k in ("reward", "value", "done"))
            advantages = torch.zeros_like(rewards)
            gae = torch.zeros(args.envs)
            for t in reversed(range(len(rewards))):
                next_value = last_value if t + 1 == len(rewards) else values[t + 1]
                delta = rewards[t] + gamma * next_value * (1 - dones[t]) - values[t]
                gae = delta + gamma * lam * (1 - dones[t]) * gae
                advantages[t] = gae
            returns = (advantages + values).flatten()
            advantages = advantages.flatten()
            advantages = (advantages - advantages.mean()) / (advantages.std() + 1e-8)
            depth = torch.cat(buf["depth"])
            state = torch.cat(buf["state"])
            actions, old_logp = torch.cat(buf["action"]), torch.cat(buf["logp"])
            n = len(returns)
            for _ in range(epochs):
                for idx in torch.randperm(n).split(minibatch):
                    dist = torch.distributions.Normal(actor(depth[idx], state[idx]), log_std.exp())
                    ratio = (dist.log_prob(actions[idx]).sum(-1) - old_logp[idx]).exp()
                    policy_loss = -torch.min(ratio * advantages[idx],
                                             ratio.clamp(1 - clip, 1 + clip) * advantages[idx]).mean()
                    value_loss = (critic(depth[idx], state[idx]) - returns[idx]).pow(2).mean()
                    loss = policy_loss + 0.5 * value_loss - 0.001 * dist.entropy().sum(-1).mean()
                    opt.zero_grad()
                    loss.backward()
                    nn.utils.clip_grad_norm_(list(actor.parameters()) + list(critic.parameters()), 0.5)
                    opt.step()
            iteration += 1
            row = np.array(finished) if finished else np.full((1, 4), np.nan)
            writer.writerow([iteration, steps, round(time.time() - start, 1), len(finished),
                             float(np.mean(row[:, 0])), float(np.mean(row[:, 1])), float(np.mean(row[:, 2])),
                             float(np.nanmean(row[:, 3])) if len(finished) else float("nan")])
            f.flush()
            print("iteration %d: %d steps, %d episodes, return %.2f, success %.2f, collisions %.2f" %
                  (iteration, steps, len(finished), np.mean(row[:, 0]), np.mean(row[:, 1]), np.mean(row[:, 2])),
                  flush=True)
            finished = []
            save_policy(actor, width, height, args.out,
                        {"trainer": "examples/torch_nav_ppo.py", "board": args.board, "latency": args.latency,
                         "world": WORLD, "world_params": WORLD_PARAMS, "env_steps": steps,
                         "iterations": iteration, "seed": args.seed}, log_std)
    envs.close()


if __name__ == "__main__":
    main()
