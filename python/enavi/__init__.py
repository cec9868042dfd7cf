"""E-Navi's frequency-adaptation problem as a Gymnasium-style environment.

Each step is one decision of E-Navi's Strategy Controller in a real flight episode on the virtual
clock (world, depth camera, navigation stack under the board's scheduler, physics): the
observation is the policy state (16 features), the action an index into the frequency grid
(f_per, f_col, f_dif), and info["action_mask"] marks the actions that satisfy the frequency
constraints C1-C4. The API follows Gymnasium's Env and VectorEnv (reset(seed=...) -> (obs, info),
step(a) -> (obs, reward, terminated, truncated, info)); see docs/rl.md.
"""

import multiprocessing as _mp

import numpy as _np

from ._enavi import EnvCore as _EnvCore

__all__ = ["Env", "VectorEnv", "make", "make_vec"]


# With Gymnasium installed (it is not part of Debian 12) Env is a gymnasium.Env with its spaces,
# so every Gymnasium wrapper and gymnasium.register(..., entry_point="enavi:Env") take it as is.
try:
    import gymnasium as _gym
except ImportError:
    _gym = None


def _spaces(obs_size, action_size):
    if _gym is None:
        return None, None
    return (_gym.spaces.Box(-_np.inf, _np.inf, shape=(obs_size,), dtype=_np.float64),
            _gym.spaces.Discrete(action_size))


class Env(_gym.Env if _gym is not None else object):
    """One environment. Episodes are deterministic: the same seed gives the same observations
    for the same actions."""

    metadata = {"render_modes": []}
    render_mode = None

    def __init__(self, world="empty", board="tx2", clock="virtual", policy="", timeout_s=0.0,
                 world_params=None, overrides=None):
        if clock != "virtual":
            raise ValueError("clock: the environment steps on the virtual clock only "
                             "(the emulated clock runs the stack in another process)")
        self._core = _EnvCore(world, board, policy, float(timeout_s),
                              {str(k): str(v) for k, v in (world_params or {}).items()},
                              {str(k): float(v) for k, v in (overrides or {}).items()})
        self.observation_size = self._core.obs_size
        self.action_size = self._core.action_size
        self.observation_space, self.action_space = _spaces(self.observation_size, self.action_size)
        self._next_seed = 1

    def reset(self, *, seed=None, options=None):
        """Starts an episode in the world generated from `seed` (default: 1, 2, 3, ...)."""
        if seed is None:
            seed = self._next_seed
        self._next_seed = int(seed) + 1
        obs, _, _, _, info = self._core.reset(int(seed))
        return obs, info

    def step(self, action):
        """Takes action (an int with info['action_mask'][action] == 1)."""
        return self._core.step(int(action))

    def close(self):
        self._core = None


def make(world="empty", **kwargs):
    """enavi.make("s1", board="pi4b"): like gymnasium.make for this environment."""
    return Env(world, **kwargs)


def _worker(conn, kwargs):
    env = Env(**kwargs)
    while True:
        cmd, arg = conn.recv()
        if cmd == "reset":
            conn.send(env.reset(seed=arg))
        elif cmd == "step":
            obs, reward, terminated, truncated, info = env.step(arg)
            if terminated or truncated:
                # Gymnasium's autoreset: the next episode starts at once; the last observation
                # of the finished one stays in info.
                info = dict(info, final_observation=obs, final_info=dict(info))
                obs, reset_info = env.reset()
                info["action_mask"] = reset_info["action_mask"]
            conn.send((obs, reward, terminated, truncated, info))
        elif cmd == "close":
            conn.close()
            return


class VectorEnv:
    """N environments in N processes, stepped together (Gymnasium's VectorEnv API, autoreset):
    observations are stacked (N, observation_size); infos are dicts of arrays."""

    def __init__(self, num_envs, **kwargs):
        if num_envs < 1:
            raise ValueError("num_envs: must be >= 1")
        self.num_envs = num_envs
        context = _mp.get_context("spawn")
        self._conns, self._procs = [], []
        for _ in range(num_envs):
            parent, child = context.Pipe()
            proc = context.Process(target=_worker, args=(child, kwargs), daemon=True)
            proc.start()
            self._conns.append(parent)
            self._procs.append(proc)
        probe = _EnvCore("empty", "tx2", "", 0.0, {}, {})
        self.observation_size, self.action_size = probe.obs_size, probe.action_size
        del probe

    @staticmethod
    def _stack_infos(infos):
        out = {}
        for key in infos[0]:
            values = [i.get(key) for i in infos]
            try:
                out[key] = _np.stack(values)
            except (ValueError, TypeError):
                out[key] = _np.array(values, dtype=object)
        return out

    def reset(self, *, seed=None, options=None):
        """Environment i starts with seed + i (default seed: 1)."""
        base = 1 if seed is None else int(seed)
        for i, c in enumerate(self._conns):
            c.send(("reset", base + i))
        results = [c.recv() for c in self._conns]
        return _np.stack([r[0] for r in results]), self._stack_infos([r[1] for r in results])

    def step(self, actions):
        for c, a in zip(self._conns, actions):
            c.send(("step", int(a)))
        results = [c.recv() for c in self._conns]
        obs, rew, term, trunc, infos = zip(*results)
        return (_np.stack(obs), _np.array(rew), _np.array(term), _np.array(trunc),
                self._stack_infos(list(infos)))

    def close(self):
        for c in self._conns:
            c.send(("close", None))
        for p in self._procs:
            p.join(timeout=10)


def make_vec(num_envs, **kwargs):
    """enavi.make_vec(4, world="s1"): a VectorEnv of num_envs processes."""
    return VectorEnv(num_envs, **kwargs)
