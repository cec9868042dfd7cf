"""Two Gymnasium-style environments on the farm's virtual-clock flights (docs/rl.md).

Env (enavi.make): E-Navi's frequency-adaptation problem. Each step is one decision of E-Navi's Strategy Controller in a real flight episode on the virtual
clock (world, depth camera, navigation stack under the board's scheduler, physics): the
observation is the policy state (16 features), the action an index into the frequency grid
(f_per, f_col, f_dif), and info["action_mask"] marks the actions that satisfy the frequency
constraints C1-C4. The API follows Gymnasium's Env and VectorEnv (reset(seed=...) -> (obs, info),
step(a) -> (obs, reward, terminated, truncated, info)); see docs/rl.md.

NavEnv (enavi.make_nav): learned navigation with the board's inference latency in the loop. Each
step is one inference of the `learned` method: the observation is {"depth": (H, W) float32 in
[0, 1], "state": (8,) float32} (goal and velocity in the vehicle's yaw frame), the action 4 values
in [-1, 1] (forward, left and up velocity and yaw rate, times 2, 2, 1 m/s and 1 rad/s); the action
takes effect when the board would have finished computing it (latency="none": at once).
"""

import multiprocessing as _mp

import numpy as _np

from ._enavi import EnvCore as _EnvCore
from ._enavi import NavEnvCore as _NavEnvCore
from ._enavi import nav_policy_forward, nav_policy_multiply_adds, save_chart_png

__all__ = ["Env", "NavEnv", "VectorEnv", "make", "make_nav", "make_vec", "make_nav_vec",
           "nav_policy_forward", "nav_policy_multiply_adds", "save_chart_png"]


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


class _SeededEnv(_gym.Env if _gym is not None else object):
    """What both environments share: reset(seed) with seeds 1, 2, 3, ... by default."""

    metadata = {"render_modes": []}
    render_mode = None
    _next_seed = 1

    def reset(self, *, seed=None, options=None):
        """Starts an episode in the world generated from `seed` (default: 1, 2, 3, ...)."""
        if seed is None:
            seed = self._next_seed
        self._next_seed = int(seed) + 1
        obs, _, _, _, info = self._core.reset(int(seed))
        return obs, info

    def close(self):
        self._core = None


class Env(_SeededEnv):
    """One environment. Episodes are deterministic: the same seed gives the same observations
    for the same actions."""

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

    def step(self, action):
        """Takes action (an int with info['action_mask'][action] == 1)."""
        return self._core.step(int(action))


def make(world="empty", **kwargs):
    """enavi.make("s1", board="pi4b"): like gymnasium.make for this environment."""
    return Env(world, **kwargs)


# Image sizes: the 640x480 sensor decimated n x n.
_DECIMATION = {(640 // n, 480 // n): n for n in range(1, 11) if 640 % n == 0 and 480 % n == 0}


class NavEnv(_SeededEnv):
    """Learned navigation on a board. Episodes are deterministic: the same seed gives the same
    observations for the same actions."""

    def __init__(self, world="forest", board="pi4b", image=(64, 48), latency="board", multiply_adds=0,
                 timeout_s=0.0, world_params=None, overrides=None):
        image = tuple(int(v) for v in image)
        if image not in _DECIMATION:
            raise ValueError("image: (width, height) of the 640x480 sensor decimated by a whole n "
                             "(one of %s), got %s" % (sorted(_DECIMATION), image))
        if latency not in ("board", "none"):
            raise ValueError("latency: 'board' or 'none', got %r" % (latency,))
        self._core = _NavEnvCore(world, board, _DECIMATION[image], latency == "none", int(multiply_adds),
                                 float(timeout_s),
                                 {str(k): str(v) for k, v in (world_params or {}).items()},
                                 {str(k): float(v) for k, v in (overrides or {}).items()})
        self.image = image
        self.multiply_adds = self._core.multiply_adds
        if _gym is not None:
            self.observation_space = _gym.spaces.Dict({
                "depth": _gym.spaces.Box(0.0, 1.0, shape=(image[1], image[0]), dtype=_np.float32),
                "state": _gym.spaces.Box(-_np.inf, _np.inf, shape=(8,), dtype=_np.float32)})
            self.action_space = _gym.spaces.Box(-1.0, 1.0, shape=(4,), dtype=_np.float32)

    def step(self, action):
        """Takes action: 4 values in [-1, 1] (clipped)."""
        return self._core.step(_np.asarray(action, dtype=_np.float64).reshape(-1))


def make_nav(world="forest", **kwargs):
    """enavi.make_nav("forest", board="pi4b", image=(64, 48), world_params={"density": 1})."""
    return NavEnv(world, **kwargs)


_ENVS = {"frequency": Env, "nav": NavEnv}


def _worker(conn, kind, kwargs):
    env = _ENVS[kind](**kwargs)
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
                if "action_mask" in reset_info:
                    info["action_mask"] = reset_info["action_mask"]
            conn.send((obs, reward, terminated, truncated, info))
        elif cmd == "close":
            conn.close()
            return


class VectorEnv:
    """N environments in N processes, stepped together (Gymnasium's VectorEnv API, autoreset):
    observations are stacked (N, ...), per key for NavEnv's; infos are dicts of arrays.
    kind: "frequency" (Env) or "nav" (NavEnv)."""

    def __init__(self, num_envs, kind="frequency", **kwargs):
        if num_envs < 1:
            raise ValueError("num_envs: must be >= 1")
        if kind not in _ENVS:
            raise ValueError("kind: one of %s, got %r" % (sorted(_ENVS), kind))
        self.num_envs = num_envs
        self.kind = kind
        context = _mp.get_context("spawn")
        self._conns, self._procs = [], []
        for _ in range(num_envs):
            parent, child = context.Pipe()
            proc = context.Process(target=_worker, args=(child, kind, kwargs), daemon=True)
            proc.start()
            self._conns.append(parent)
            self._procs.append(proc)
        if kind == "frequency":
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
        return self._stack_obs([r[0] for r in results]), self._stack_infos([r[1] for r in results])

    @staticmethod
    def _stack_obs(obs):
        if isinstance(obs[0], dict):
            return {k: _np.stack([o[k] for o in obs]) for k in obs[0]}
        return _np.stack(obs)

    def step(self, actions):
        for c, a in zip(self._conns, actions):
            c.send(("step", int(a) if self.kind == "frequency" else _np.asarray(a, dtype=_np.float64)))
        results = [c.recv() for c in self._conns]
        obs, rew, term, trunc, infos = zip(*results)
        return (self._stack_obs(list(obs)), _np.array(rew), _np.array(term), _np.array(trunc),
                self._stack_infos(list(infos)))

    def close(self):
        for c in self._conns:
            c.send(("close", None))
        for p in self._procs:
            p.join(timeout=10)


def make_vec(num_envs, **kwargs):
    """enavi.make_vec(4, world="s1"): a VectorEnv of num_envs processes."""
    return VectorEnv(num_envs, **kwargs)


def make_nav_vec(num_envs, **kwargs):
    """enavi.make_nav_vec(2, world="forest", board="pi4b"): NavEnvs in num_envs processes."""
    return VectorEnv(num_envs, kind="nav", **kwargs)
