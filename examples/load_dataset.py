#!/usr/bin/env python3
"""Loads an exported dataset (enavi dataset export JOB --out DIR) with numpy and checks it against
its schema.json: every documented array in every shard, one row per transition, shapes as
documented, each episode exactly once. Either kind: E-Navi's frequency decisions ("frequency") or
the learned method's depth images and velocity commands ("nav").

    python3 examples/load_dataset.py DIR [--episodes N]
"""

import argparse
import json
import os
import sys

import numpy as np


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("dir")
    parser.add_argument("--episodes", type=int, help="expected number of episodes")
    args = parser.parse_args()

    with open(os.path.join(args.dir, "schema.json")) as f:
        schema = json.load(f)
    assert schema["format"] == "enavi-rollout-dataset", schema["format"]
    kind = schema.get("kind", "frequency")
    names = [a["name"] for a in schema["arrays"]]

    steps, episode_ids, pairs = 0, set(), set()
    for shard in schema["shards"]:
        with np.load(os.path.join(args.dir, shard["file"])) as data:
            missing = set(names) - set(data.files)
            assert not missing, f"{shard['file']}: missing arrays {sorted(missing)}"
            n = data["action"].shape[0]
            assert n == shard["steps"], (shard["file"], n, shard["steps"])
            for name in names:
                assert data[name].shape[0] == n, (shard["file"], name, data[name].shape)
            if kind == "nav":
                image = schema["image"]
                assert data["depth"].shape == (n, image["height"], image["width"])
                assert data["depth"].dtype == np.uint16
                assert data["state"].shape == (n, 8) and data["action"].shape == (n, 4)
                assert np.isfinite(data["action"]).all() and np.isfinite(data["log_prob"]).all()
            else:
                assert data["obs"].shape == (n, schema["obs_dim"])
                assert data["mask"].shape == (n, schema["num_actions"]) and data["mask"].dtype == np.bool_
                # Every action was feasible when it was taken; log-probabilities are <= 0.
                assert data["mask"][np.arange(n), data["action"]].all()
                assert (data["log_prob"] <= 0).all()
            # Episodes never straddle shards and end with a terminal or a truncation.
            ends = data["done"] | data["truncated"]
            assert ends[-1]
            for e in np.unique(data["episode_id"]):
                rows = np.flatnonzero(data["episode_id"] == e)
                assert (np.diff(rows) == 1).all() and ends[rows[-1]] and ends[rows].sum() == 1
                assert (data["step"][rows] == np.arange(len(rows))).all()
                assert e not in episode_ids, f"episode {e} twice"
                episode_ids.add(str(e))
            pairs |= set(zip(data["episode"].tolist(), data["episode_id"].tolist()))
            steps += n

    assert steps == schema["steps"], (steps, schema["steps"])
    assert len(episode_ids) == schema["episodes"] == len(schema["episode_table"])
    assert len(pairs) == len(episode_ids), "episode index and id disagree"
    if args.episodes is not None:
        assert len(episode_ids) == args.episodes, (len(episode_ids), args.episodes)
    print(f"{args.dir}: {kind}, {len(episode_ids)} episodes, {steps} transitions, "
          f"{len(schema['shards'])} shards: ok")


if __name__ == "__main__":
    sys.exit(main())
