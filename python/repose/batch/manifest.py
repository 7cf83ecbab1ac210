"""The batch manifest (YAML or JSON): subjects and what to make of each, checked as a whole before
anything runs, every path resolved against the manifest's folder. See docs/batch.md."""
import json
import os
import re

from repose import vtkReposeCorotationalRelax

LABEL_FORMATS = (".nii.gz", ".nii", ".nrrd", ".nhdr", ".mha", ".mhd")
OUTPUTS = ("labels", "mesh", "surfaces", "image")
# `repose prepare` options a subject may set, manifest key -> option.
PREPARE_OPTIONS = {"mesh_spacing": "--mesh-spacing", "quality": "--quality", "influences": "--influences",
                   "surface_reduction": "--surface-reduction", "body_threshold": "--body-threshold",
                   "max_gap": "--max-gap"}
RELAX_DEFAULTS = {"model": "fixed-corotated", "volume": "segments", "continuation": "if-inverted",
                  "strained_region": "first", "poisson": 0.49, "iterations": 1}


def _relax_words(setting):
    """The relaxation filter's words for a setting, as `repose pose --relax-*` takes them."""
    relax = vtkReposeCorotationalRelax
    return tuple(relax.GetWord(setting, i) for i in range(relax.GetNumberOfWords(setting)))


RELAX_CHOICES = {"model": _relax_words("model"), "volume": _relax_words("volume"),
                 "continuation": _relax_words("continuation"), "strained_region": ("first", "off")}
SETTING_KEYS = ("prepare", "skinning", "relax", "outputs", "format")
SUBJECT_KEYS = ("name", "labels", "image", "skeleton", "label_table", "poses", "clips") + SETTING_KEYS
CLIP_KEYS = ("file", "name", "frames", "map", "mode", "reference_frame", "root_motion", "unit_mm")
SAFE_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.+-]*$")


class ManifestError(Exception):
    """A problem with the manifest; the message names the manifest and the entry."""


def read_manifest(path):
    """The manifest file parsed: JSON for .json, YAML otherwise (Debian's python3-yaml)."""
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise ManifestError(f"{path}: cannot read ({e.strerror})") from None
    except UnicodeDecodeError:
        raise ManifestError(f"{path}: not UTF-8 text") from None
    try:
        if path.lower().endswith(".json"):
            data = json.loads(text)
        else:
            import yaml
            data = yaml.safe_load(text)
    except Exception as e:  # JSON and YAML syntax errors: one line with the position
        raise ManifestError(f"{path}: not valid {'JSON' if path.lower().endswith('.json') else 'YAML'} "
                            f"({' '.join(str(e).split())})") from None
    if not isinstance(data, dict) or not isinstance(data.get("subjects"), list) or not data["subjects"]:
        raise ManifestError(f"{path}: needs a list 'subjects' (see docs/batch.md)")
    return data


class _Checker:
    """Checks entries of one manifest; every error names the manifest and where in it."""

    def __init__(self, path):
        self.path = path
        self.base = os.path.dirname(os.path.abspath(path))

    def fail(self, where, message):
        raise ManifestError(f"{self.path}: {where}: {message}")

    def keys(self, entry, allowed, where):
        if not isinstance(entry, dict):
            self.fail(where, "must be a mapping")
        unknown = sorted(set(entry) - set(allowed))
        if unknown:
            self.fail(where, f"unknown key '{unknown[0]}' (known: {', '.join(allowed)})")

    def file(self, value, where, folder=False):
        """A file (folder=True: a folder; folder=None: either, as a CT file or a DICOM series folder)."""
        if not isinstance(value, str) or not value:
            self.fail(where, "needs a file name")
        path = os.path.normpath(os.path.join(self.base, os.path.expanduser(value)))
        found = os.path.exists(path) if folder is None else os.path.isdir(path) if folder else os.path.isfile(path)
        if not found:
            self.fail(where, f"{path}: no such {'file or folder' if folder is None else 'folder' if folder else 'file'}")
        return path

    def number(self, value, where, whole=False):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or (whole and value != int(value)):
            self.fail(where, f"needs {'a whole number' if whole else 'a number'}, not {value!r}")
        return int(value) if whole else float(value)

    def name(self, value, where):
        if not isinstance(value, str) or not SAFE_NAME.match(value):
            self.fail(where, f"name {value!r} must be letters, digits, '_', '.', '+' or '-' (it names a folder)")
        return value

    def settings(self, entry, inherited, where):
        """The posing and preparing settings of a subject: its own over the manifest's."""
        s = dict(inherited)
        if "prepare" in entry:
            self.keys(entry["prepare"], tuple(PREPARE_OPTIONS), f"{where}.prepare")
            s["prepare"] = {**s["prepare"], **{k: self.number(v, f"{where}.prepare.{k}")
                                                for k, v in entry["prepare"].items()}}
        if "skinning" in entry:
            if entry["skinning"] not in ("dqs", "lbs"):
                self.fail(f"{where}.skinning", f"must be dqs or lbs, not {entry['skinning']!r}")
            s["skinning"] = entry["skinning"]
        if "relax" in entry:
            s["relax"] = self.relax(entry["relax"], f"{where}.relax")
        if "outputs" in entry:
            outputs = entry["outputs"]
            if not isinstance(outputs, list) or not outputs or any(o not in OUTPUTS for o in outputs):
                self.fail(f"{where}.outputs", f"must list some of {', '.join(OUTPUTS)}")
            s["outputs"] = [o for o in OUTPUTS if o in outputs]
        if "format" in entry:
            fmt = entry["format"]
            fmt = fmt if not isinstance(fmt, str) or fmt.startswith(".") else "." + fmt
            if fmt not in LABEL_FORMATS:
                self.fail(f"{where}.format", f"must be one of {', '.join(LABEL_FORMATS)}, not {entry['format']!r}")
            s["format"] = fmt
        return s

    def relax(self, value, where):
        if value is False or value is None:
            return None
        if value is True:
            return dict(RELAX_DEFAULTS)
        self.keys(value, tuple(RELAX_DEFAULTS), where)
        r = dict(RELAX_DEFAULTS)
        for k, v in value.items():
            if k in RELAX_CHOICES:
                if v not in RELAX_CHOICES[k]:
                    self.fail(f"{where}.{k}", f"must be one of {', '.join(RELAX_CHOICES[k])}, not {v!r}")
                r[k] = v
            else:
                r[k] = self.number(v, f"{where}.{k}", whole=(k == "iterations"))
        if not -1 < r["poisson"] < 0.5:
            self.fail(f"{where}.poisson", "must be in (-1, 0.5)")
        if r["iterations"] < 1:
            self.fail(f"{where}.iterations", "must be at least 1")
        return r


def _stem(path):
    name = os.path.basename(path)
    for ext in LABEL_FORMATS + (".json", ".bvh"):
        if name.lower().endswith(ext):
            return name[: -len(ext)]
    return os.path.splitext(name)[0]


def bvh_frame_count(path):
    """The 'Frames: N' line of a BVH file's MOTION section (the clip itself is read on the workers)."""
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            m = re.match(r"\s*Frames:\s*(\d+)\s*$", line)
            if m:
                return int(m.group(1))
    raise ValueError("no 'Frames:' line (not a BVH clip)")


def frame_range(text, count):
    """Frames A:B:S as `repose animate --frames` selects them: A inclusive to B exclusive (clamped to
    the clip) every S; empty = all."""
    if text is None or text == "":
        return list(range(count))
    parts = str(text).split(":")
    if len(parts) > 3:
        raise ValueError(f"frames needs START:STOP:STEP, not '{text}'")
    try:
        values = [int(p) if p.strip() else None for p in parts] + [None] * (3 - len(parts))
    except ValueError:
        raise ValueError(f"frames needs whole numbers, not '{text}'") from None
    start = values[0] or 0
    stop = count if values[1] is None else min(values[1], count)
    step = 1 if values[2] is None else values[2]
    if start < 0 or start >= count or step < 1 or stop <= start:
        raise ValueError(f"frames {text} selects no frame of a clip with {count} frames")
    return list(range(start, stop, step))


def _poses(c, entry, where):
    poses = []
    for i, p in enumerate(entry.get("poses") or []):
        at = f"{where}.poses[{i}]"
        if isinstance(p, str):
            p = {"file": p}
        c.keys(p, ("name", "file", "pose"), at)
        if ("file" in p) == ("pose" in p):
            c.fail(at, "needs either 'file' (a pose.json) or 'pose' (the pose itself)")
        if "file" in p:
            path = c.file(p["file"], f"{at}.file")
            name = c.name(p.get("name", _stem(path)), f"{at}.name")
            poses.append({"name": name, "file": path})
        else:
            if not isinstance(p["pose"], dict):
                c.fail(f"{at}.pose", "must be a pose.json mapping (rotations, translation)")
            name = c.name(p.get("name"), f"{at}.name")
            poses.append({"name": name, "text": json.dumps(p["pose"], indent=2) + "\n"})
    return poses


def _clips(c, entry, where):
    clips = []
    for i, clip in enumerate(entry.get("clips") or []):
        at = f"{where}.clips[{i}]"
        if isinstance(clip, str):
            clip = {"file": clip}
        c.keys(clip, CLIP_KEYS, at)
        path = c.file(clip.get("file"), f"{at}.file")
        try:
            frames = frame_range(clip.get("frames"), bvh_frame_count(path))
        except (OSError, ValueError) as e:
            c.fail(at, f"{path}: {e}")
        mode = clip.get("mode", "direction")
        if mode not in ("direction", "relative"):
            c.fail(f"{at}.mode", f"must be direction or relative, not {mode!r}")
        clips.append({
            "name": c.name(clip.get("name", _stem(path)), f"{at}.name"), "file": path, "frames": frames,
            "map": c.file(clip["map"], f"{at}.map") if clip.get("map") else None, "mode": mode,
            "reference_frame": c.number(clip.get("reference_frame", 0), f"{at}.reference_frame", whole=True),
            "root_motion": bool(clip.get("root_motion", True)),
            "unit_mm": c.number(clip.get("unit_mm", 0), f"{at}.unit_mm")})  # 0: inferred
    return clips


def _unique(c, items, what, where):
    seen = set()
    for item in items:
        if item["name"] in seen:
            c.fail(where, f"two {what} are named '{item['name']}' (their outputs would collide)")
        seen.add(item["name"])


def load_manifest(path):
    """The manifest checked and resolved: {"path", "data", "subjects": [...]}, each subject with
    absolute paths, its settings (its own over the manifest's `settings`), poses and clips."""
    data = read_manifest(path)
    c = _Checker(path)
    c.keys(data, ("settings", "subjects"), "top level")
    defaults = {"prepare": {}, "skinning": "dqs", "relax": None, "outputs": list(OUTPUTS), "format": None}
    if "settings" in data:
        c.keys(data["settings"], SETTING_KEYS, "settings")
        defaults = c.settings(data["settings"], defaults, "settings")
    subjects = []
    for i, entry in enumerate(data["subjects"]):
        where = f"subjects[{i}]"
        c.keys(entry, SUBJECT_KEYS, where)
        labels = c.file(entry.get("labels"), f"{where}.labels")
        name = c.name(entry.get("name", _stem(labels)), f"{where}.name")
        where = f"subjects[{i}] ({name})"
        skeleton = entry.get("skeleton", "auto")
        subject = {
            "name": name, "labels": labels,
            "skeleton": "auto" if skeleton == "auto" else c.file(skeleton, f"{where}.skeleton"),
            "image": c.file(entry["image"], f"{where}.image", folder=None) if entry.get("image") else None,
            "label_table": c.file(entry["label_table"], f"{where}.label_table") if entry.get("label_table") else None,
            "settings": c.settings(entry, defaults, where),
            "poses": _poses(c, entry, where), "clips": _clips(c, entry, where)}
        if not subject["poses"] and not subject["clips"]:
            c.fail(where, "names no poses and no clips")
        _unique(c, subject["poses"], "poses", where)
        _unique(c, subject["clips"], "clips", where)
        subjects.append(subject)
    _unique(c, subjects, "subjects", "subjects")
    return {"path": os.path.abspath(path), "data": data, "subjects": subjects}
