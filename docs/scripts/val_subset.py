"""Write a dataset folder whose ``index.csv`` names a training run's validation fingers.

The frames stay where they are (paths relative to the new folder); only the fingers of the
run's ``config.json`` split (``"val"``, each key read as the ``data_dirs`` folder it names:
``contactcal.train.split.recorded_split``) from datasets whose folder name contains ``--match``
are kept, renumbered, with the source folder in the session name. ``contactcal bench --data OUT
--robustness`` then measures on validation frames only (``docs/training.md``, "The whole blur
kernel"). The index is written all or nothing; an existing ``index.csv`` in OUT is not replaced.

    .venv/bin/python docs/scripts/val_subset.py runs/h6 --match hires --out data/val_hr
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
from pathlib import Path

from contactcal.train.split import recorded_split


def val_rows(run: Path, match: str, out: Path) -> list[dict[str, str]]:
    """The index rows of the run's validation fingers, re-rooted at ``out``."""
    path = run / "config.json"
    split = recorded_split(json.loads(path.read_text(encoding="utf-8")), path)["val"]
    keys = [
        key.rpartition("#") for key in split
    ]  # <folder>#<finger>: the finger follows the last #
    kept = [(Path(folder), finger) for folder, _, finger in keys if match in Path(folder).name]
    rows = []
    for n, (src, finger) in enumerate(kept):
        with open(src / "index.csv", newline="", encoding="utf-8") as f:
            for r in csv.DictReader(f):
                if r["finger"] != finger:
                    continue
                rel = Path(os.path.relpath(src, out))
                r.update(
                    finger=str(n),
                    session=f"{src.name}_{r['session']}",
                    frame=str(rel / r["frame"]),
                    mask=str(rel / r["mask"]),
                )
                rows.append(r)
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="training run folder (config.json)")
    ap.add_argument("--match", default="", help="keep datasets whose folder name contains this")
    ap.add_argument("--out", type=Path, required=True, help="new dataset folder")
    args = ap.parse_args()
    index = args.out / "index.csv"
    if index.exists():
        print(f"{index}: exists; choose another --out", file=sys.stderr)
        return 2
    try:
        rows = val_rows(args.run, args.match, args.out)
    except (OSError, ValueError) as exc:
        print(exc, file=sys.stderr)
        return 2
    if not rows:
        print(f"{args.run}: no validation finger matches {args.match!r}", file=sys.stderr)
        return 2
    args.out.mkdir(parents=True, exist_ok=True)
    tmp = index.with_suffix(".csv.tmp")
    with open(tmp, "w", newline="", encoding="utf-8") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    tmp.replace(index)
    print(f"wrote {index}: {len({r['finger'] for r in rows})} fingers, {len(rows)} frames")
    return 0


if __name__ == "__main__":
    sys.exit(main())
