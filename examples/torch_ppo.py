#!/usr/bin/env python3
"""A short PPO run with PyTorch on the enavi environment: a masked-categorical actor-critic (the
same architecture family as E-Navi's policy, smaller), clipped surrogate objective, GAE.

    PYTHONPATH=build/python python3 examples/torch_ppo.py [--steps 300] [--world empty]
"""

import argparse

import numpy as np
import torch
from torch import nn

import enavi


class ActorCritic(nn.Module):
    def __init__(self, obs_size, action_size, hidden=64):
        super().__init__()
        self.actor = nn.Sequential(nn.Linear(obs_size, hidden), nn.Tanh(), nn.Linear(hidden, action_size))
        self.critic = nn.Sequential(nn.Linear(obs_size, hidden), nn.Tanh(), nn.Linear(hidden, 1))

    def dist(self, obs, mask):
        logits = self.actor(obs).masked_fill(~mask, -1e9)
        return torch.distributions.Categorical(logits=logits)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=300, help="environment steps")
    parser.add_argument("--world", default="empty")
    parser.add_argument("--board", default="tx2")
    parser.add_argument("--batch", type=int, default=100)
    args = parser.parse_args()
    torch.manual_seed(1)

    env = enavi.make(args.world, board=args.board)
    net = ActorCritic(env.observation_size, env.action_size)
    opt = torch.optim.Adam(net.parameters(), lr=3e-4)
    # Observations are raw features of different scales: a running mean/var normalises them.
    mean, var, count = np.zeros(env.observation_size), np.ones(env.observation_size), 1e-4

    obs, info = env.reset(seed=100)
    seed, steps, returns, episode_return = 100, 0, [], 0.0
    while steps < args.steps:
        batch = {k: [] for k in ("obs", "mask", "action", "logp", "value", "reward", "done")}
        for _ in range(args.batch):
            count += 1
            delta = obs - mean
            mean += delta / count
            var += (delta * (obs - mean) - var) / count
            o = torch.as_tensor((obs - mean) / np.sqrt(var + 1e-8), dtype=torch.float32)
            m = torch.as_tensor(info["action_mask"] > 0)
            with torch.no_grad():
                d = net.dist(o, m)
                a = d.sample()
                v = net.critic(o).squeeze()
            obs, reward, terminated, truncated, info = env.step(int(a))
            for k, x in zip(batch, (o, m, a, d.log_prob(a), v, reward, terminated or truncated)):
                batch[k].append(x)
            episode_return += reward
            steps += 1
            if terminated or truncated:
                returns.append(episode_return)
                episode_return = 0.0
                seed += 1
                obs, info = env.reset(seed=seed)
        # GAE (gamma 0.99, lambda 0.95); an episode cut by the batch end bootstraps with V = 0.
        rewards = np.array(batch["reward"])
        dones = np.array(batch["done"], dtype=np.float64)
        values = torch.stack(batch["value"]).numpy()
        adv, gae = np.zeros_like(rewards), 0.0
        for t in reversed(range(len(rewards))):
            next_value = 0.0 if t + 1 == len(rewards) else values[t + 1]
            delta = rewards[t] + 0.99 * next_value * (1 - dones[t]) - values[t]
            gae = delta + 0.99 * 0.95 * (1 - dones[t]) * gae
            adv[t] = gae
        ret = torch.as_tensor(adv + values, dtype=torch.float32)
        adv = torch.as_tensor((adv - adv.mean()) / (adv.std() + 1e-8), dtype=torch.float32)
        o, m = torch.stack(batch["obs"]), torch.stack(batch["mask"])
        a, old_logp = torch.stack(batch["action"]), torch.stack(batch["logp"])
        for _ in range(4):
            d = net.dist(o, m)
            ratio = torch.exp(d.log_prob(a) - old_logp)
            policy_loss = -torch.min(ratio * adv, torch.clamp(ratio, 0.8, 1.2) * adv).mean()
            value_loss = 0.5 * (net.critic(o).squeeze(-1) - ret).pow(2).mean()
            loss = policy_loss + 0.5 * value_loss - 0.01 * d.entropy().mean()
            opt.zero_grad()
            loss.backward()
            nn.utils.clip_grad_norm_(net.parameters(), 0.5)
            opt.step()
        assert torch.isfinite(loss), "PPO loss is not finite"
        print(f"steps {steps}: loss {loss.item():.4f}  policy {policy_loss.item():.4f}  "
              f"value {value_loss.item():.4f}  episodes {len(returns)}  "
              f"mean return {np.mean(returns) if returns else float('nan'):.2f}")
    assert returns, "no episode finished"


if __name__ == "__main__":
    main()
