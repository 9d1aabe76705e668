"""Videos of the games: an H.264 mp4 writer, and `record`, a rollout played straight into a file.

    from octax_gym import video
    result = video.record("Pong", "pong.mp4", steps=600, num_envs=4)   # a 2 x 2 grid, random agent

Gymnasium's `RecordVideo` wrappers also work on our envs (docs/video.md); this module is for when
you want one file of a fixed number of steps, a grid of many envs, or a policy of your own.
Frames are streamed to ffmpeg as they are rendered, never held in memory: a 4-env grid at the
default scale is 1.6 MB a frame. The ffmpeg binary is imageio-ffmpeg's (it has libx264), so no
system ffmpeg is needed; it and the encoder are loaded only when a video is written.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import os
import subprocess
import tempfile
from fractions import Fraction
from pathlib import Path
from typing import Iterable, Iterator, Union

import gymnasium
import numpy as np
from tqdm import tqdm

from octax_core.validate import check_int
from octax_gym.envs import render
from octax_gym.envs.game_names import resolve_env_id
from octax_gym.policies import Act, Policy, check_policy, make_policy

VIDEO_EXTRA_HINT = "pip install 'octax-gym[video]'"
# x264's constant-quality setting: 18 is about visually lossless, and flat pixel art still
# compresses to a few kB a second, so there is no reason to trade sharpness for size.
CRF = 18


@dataclasses.dataclass(frozen=True)
class RecordResult:
    """What `record` wrote: the file, its frame count and size, and the episodes that ended.

    `episodes` counts episode ends (terminated or truncated) over every env of the grid.
    """

    path: Path
    frames: int
    episodes: int
    width: int
    height: int
    fps: float

    @property
    def seconds(self) -> float:
        return self.frames / self.fps


# --- the writer -------------------------------------------------------------------------------


def write_mp4(frames: Iterable[np.ndarray], path: Union[str, os.PathLike], fps: float) -> int:
    """Encodes frames as an H.264 mp4 (libx264, yuv420p, so browsers play it); returns the count.

    Frames are consumed one at a time, so `frames` may be a generator of any length. The parent
    folder is created if needed; if anything fails, the partial file is removed.

    Args:
        frames: uint8 arrays (H, W, 3), RGB, all one shape; H and W even (4:2:0 chroma halves both).
        path: the output file; must end in ".mp4".
        fps: frames per second, > 0 (our envs: `metadata["render_fps"]`, 60 / frames_per_step).

    Raises:
        ImportError: imageio-ffmpeg (the `video` extra) is not installed.
        ValueError: a bad path, fps or frame (the message says which and why), or no frames.
        OSError: ffmpeg failed (its error output is in the message).
    """
    path = _check_mp4_path(path)
    fps = _check_fps(fps)
    ffmpeg = _ffmpeg_exe()
    frames = iter(frames)
    first = next(frames, None)
    if first is None:
        raise ValueError("write_mp4 got no frames")
    shape = _check_frame(first, 0, None)
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryFile() as log:  # a file, not a pipe: a full stderr pipe would block ffmpeg
        process = subprocess.Popen(_ffmpeg_command(ffmpeg, path, shape, fps), stdin=subprocess.PIPE,
                                   stdout=subprocess.DEVNULL, stderr=log)
        try:
            count = _feed(process, itertools.chain([first], frames), shape)
        except BaseException:
            process.kill()
            process.wait()
            _remove_partial(path)
            raise
        if process.wait() != 0:
            log.seek(0)
            _remove_partial(path)
            raise OSError(f"ffmpeg failed writing {path} (exit {process.returncode}): "
                          + log.read().decode(errors="replace").strip())
    return count


def _feed(process: subprocess.Popen, frames: Iterator[np.ndarray], shape: tuple[int, ...]) -> int:
    """Writes every frame to ffmpeg's stdin and closes it; returns how many were written."""
    count = 0
    try:
        for index, frame in enumerate(frames):
            _check_frame(frame, index, shape)
            process.stdin.write(np.ascontiguousarray(frame).data)
            count += 1
    except BrokenPipeError:
        pass  # ffmpeg exited early; its exit status and log say why
    finally:
        try:
            process.stdin.close()
        except BrokenPipeError:
            pass
    return count


def _remove_partial(path: Path) -> None:
    if path.is_file():  # never a folder that happens to carry the name
        path.unlink()


def _ffmpeg_command(ffmpeg: str, path: Path, shape: tuple[int, ...], fps: Fraction) -> list[str]:
    height, width, _ = shape
    return [ffmpeg, "-y", "-loglevel", "error",
            "-f", "rawvideo", "-pix_fmt", "rgb24", "-s", f"{width}x{height}", "-r", str(fps), "-i", "-",
            "-an", "-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", str(CRF),
            "-movflags", "+faststart",  # index first, so a browser starts playing before the end arrives
            str(path)]


def _ffmpeg_exe() -> str:
    try:
        import imageio_ffmpeg
    except ImportError as exc:
        raise ImportError("writing mp4 files needs imageio-ffmpeg (an ffmpeg with libx264): "
                          f"{VIDEO_EXTRA_HINT}") from exc
    return imageio_ffmpeg.get_ffmpeg_exe()


def _check_mp4_path(path) -> Path:
    path = Path(path).expanduser()
    if path.suffix.lower() != ".mp4":
        raise ValueError(f"the video path must end in .mp4 (H.264 in an MP4 container), got {str(path)!r}")
    return path


def _check_fps(fps) -> Fraction:
    if isinstance(fps, bool) or not isinstance(fps, (int, float, Fraction, np.number)) \
            or not math.isfinite(fps) or fps <= 0:
        raise ValueError(f"fps must be a positive number, got {fps!r}")
    # ffmpeg takes a rational: 60 / 7 frames per step is exactly "60/7", not a rounded float.
    return Fraction(fps).limit_denominator(1000)


def _check_frame(frame, index: int, shape) -> tuple[int, ...]:
    """The frame's shape, after checking it is uint8 (H, W, 3), even-sided, and like the first."""
    if not isinstance(frame, np.ndarray) or frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3:
        raise ValueError(f"frame {index}: expected a uint8 numpy array (H, W, 3), got "
                         f"{type(frame).__name__} {getattr(frame, 'dtype', '')} {getattr(frame, 'shape', '')}")
    if shape is None and (frame.shape[0] % 2 or frame.shape[1] % 2):
        raise ValueError(f"frame sides must be even for H.264 with 4:2:0 chroma, got {frame.shape[:2]} "
                         "(render.tile rounds grids up to even sides)")
    if shape is not None and frame.shape != shape:
        raise ValueError(f"frame {index}: every frame must have the first one's shape {shape}, got {frame.shape}")
    return frame.shape


# --- recording a rollout ----------------------------------------------------------------------


def record(game: str, out: Union[str, os.PathLike], *, steps: int, policy: Policy = "random",
           num_envs: int = 1, seed: int = 0, progress: bool = True, **env_kwargs) -> RecordResult:
    """Plays `steps` steps of a game in `num_envs` envs and writes them as an H.264 mp4.

    The video holds the first screen after reset plus one frame per step (steps + 1 frames), at
    the env's `render_fps` (60 / frames_per_step: real time). With several envs each frame is a
    grid (`render.tile`), env 0 top left. Envs autoreset (Gymnasium's next-step mode), so the
    video runs on through episode ends.

    Args:
        game: a game id ("Pong") or its Gymnasium id ("octax/Pong-v0"), in any case.
        out: the .mp4 file to write (its folder is created if needed).
        steps: env steps to play, >= 1.
        policy: None or "random", "noop" (`octax_gym.policies.POLICIES`), or a function from
            the batched observation (num_envs, frames_per_step, 32, 64) to a batch of actions.
        num_envs: envs shown side by side, >= 1.
        seed: seeds the envs (env i gets seed + i) and the random policy (numpy's generator).
        progress: show a tqdm progress bar (on stderr).
        **env_kwargs: `gymnasium.make_vec` keywords, e.g. render_scale=4, palette="amber",
            frames_per_step=2, max_episode_steps=500.

    Returns:
        A `RecordResult`: the path, frames written, episodes ended, frame width and height, fps.

    Raises:
        UnknownOptionError: an unknown game, policy or palette; the message lists the valid choices.
        ValueError: steps or num_envs < 1 (UnknownOptionError is a ValueError too).
        ImportError: the `video` extra is missing (checked before any emulation).
    """
    gym_id = resolve_env_id(game)
    check_int("steps", steps)
    check_int("num_envs", num_envs)
    check_policy(policy)
    path = _check_mp4_path(out)
    _ffmpeg_exe()  # fail before minutes of compiling and playing, not after
    envs = gymnasium.make_vec(gym_id, num_envs=num_envs, render_mode="rgb_array", **env_kwargs)
    try:
        act = make_policy(policy, num_envs, int(envs.single_action_space.n), seed)
        rollout = _Rollout(envs, act)
        first = rollout.reset(seed)
        bar = tqdm(total=steps, desc=f"recording {gym_id}", unit="step", disable=not progress)
        with bar:
            count = write_mp4(itertools.chain([first], rollout.frames(steps, bar)), path,
                              envs.metadata["render_fps"])
    finally:
        envs.close()
    return RecordResult(path=path, frames=count, episodes=rollout.episodes, width=first.shape[1],
                        height=first.shape[0], fps=float(envs.metadata["render_fps"]))


class _Rollout:
    """Steps a vector env with a policy and renders each step as one frame, counting episode ends."""

    def __init__(self, envs: gymnasium.vector.VectorEnv, act: Act):
        self.envs, self.act = envs, act
        self.obs = None
        self.episodes = 0

    def reset(self, seed: int) -> np.ndarray:
        self.obs, _ = self.envs.reset(seed=seed)
        return self.frame()

    def frames(self, steps: int, bar: tqdm) -> Iterator[np.ndarray]:
        for _ in range(steps):
            self.obs, _, terminated, truncated, _ = self.envs.step(self.act(self.obs))
            self.episodes += int(np.count_nonzero(np.asarray(terminated) | np.asarray(truncated)))
            bar.update()
            yield self.frame()

    def frame(self) -> np.ndarray:
        screens = self.envs.render()
        return screens[0] if len(screens) == 1 else render.tile(screens)
