"""Videos (octax_gym/video.py, `octax-gym record`) and Gymnasium's RecordVideo wrappers on our envs.

Every mp4 is read back with OpenCV: frame count (decoded, not the header's), size, codec, fps and
pixels. The envs render at scale 2 (128 x 64 a game) to keep encoding cheap; render settings are
host-side, so these tests share two compiled Pong programs (1 env and 4 envs) per worker.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import cv2
import gymnasium as gym
import numpy as np
import pytest

import octax_gym
from octax_gym import cli, video
from octax_gym.envs import render
from octax_gym.envs.game_names import resolve_env_id
from octax_gym.policies import POLICIES

H264_FOURCCS = {"avc1", "h264"}
SCALE = 2
STEPS = 30  # Pong serves after 24 steps, from a height drawn from each env's key: by now envs differ
CELL = (32 * SCALE, 64 * SCALE)  # one game's frame (height, width) at SCALE


def read_mp4(path: Path) -> tuple[list[np.ndarray], str, float]:
    """Every decoded frame (RGB), the FourCC and the fps of an mp4."""
    capture = cv2.VideoCapture(str(path))
    assert capture.isOpened(), f"OpenCV cannot open {path}"
    fourcc = int(capture.get(cv2.CAP_PROP_FOURCC)).to_bytes(4, "little").decode("ascii", "replace")
    fps = capture.get(cv2.CAP_PROP_FPS)
    frames = []
    while True:
        ok, frame = capture.read()
        if not ok:
            break
        frames.append(cv2.cvtColor(frame, cv2.COLOR_BGR2RGB))
    capture.release()
    return frames, fourcc, fps


def video_stream(path: Path) -> str:
    """ffmpeg's one-line description of the file's video stream (codec, pixel format, size, fps)."""
    import imageio_ffmpeg

    probe = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(path)],
                           check=False, capture_output=True, text=True)  # exits 1: no output file named
    streams = [line.strip() for line in probe.stderr.splitlines() if "Video:" in line]
    assert len(streams) == 1, probe.stderr
    return streams[0]


def mean_abs_diff(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a.astype(np.int16) - b.astype(np.int16)).mean())


# --- write_mp4 (no emulation) -----------------------------------------------------------------


def bar_frames(count: int, height: int = 64, width: int = 128) -> list[np.ndarray]:
    """Frame i: black, with a white bar 8 pixels wide starting at column 8 * i."""
    frames = []
    for index in range(count):
        frame = np.zeros((height, width, 3), np.uint8)
        frame[:, 8 * index: 8 * index + 8] = 255
        frames.append(frame)
    return frames


@pytest.mark.parametrize("fps", [15.0, 60 / 7])
def test_write_mp4_writes_every_frame_as_h264(tmp_path, fps):
    path = tmp_path / "sub" / "bars.mp4"  # the folder is created
    frames = bar_frames(12)
    assert video.write_mp4(iter(frames), path, fps) == 12  # a generator is fine
    decoded, fourcc, read_fps = read_mp4(path)
    assert fourcc.lower() in H264_FOURCCS
    assert "h264" in video_stream(path) and "yuv420p" in video_stream(path)  # what browsers play
    assert read_fps == pytest.approx(fps, rel=1e-3)
    assert len(decoded) == 12
    assert decoded[0].shape == (64, 128, 3)
    for index, frame in enumerate(decoded):  # the bar is where it was drawn: order and pixels kept
        assert int(np.argmax(frame[..., 0].mean(axis=0))) // 8 == index
        assert mean_abs_diff(frame, frames[index]) < 4


@pytest.mark.parametrize("frames, path, fps, match", [
    (bar_frames(2, 63, 128), "v.mp4", 15, "even"),
    (bar_frames(2, 64, 126)[:1] + bar_frames(2)[1:], "v.mp4", 15, r"first one's shape \(64, 126, 3\)"),
    ([np.zeros((64, 128, 3), np.float32)], "v.mp4", 15, "uint8"),
    ([np.zeros((64, 128), np.uint8)], "v.mp4", 15, r"\(H, W, 3\)"),
    ([], "v.mp4", 15, "no frames"),
    (bar_frames(2), "v.avi", 15, r"\.mp4"),
    (bar_frames(2), "v.mp4", 0, "fps"),
    (bar_frames(2), "v.mp4", float("nan"), "fps"),
])
def test_write_mp4_rejects_bad_input_and_leaves_no_file(tmp_path, frames, path, fps, match):
    with pytest.raises(ValueError, match=match):
        video.write_mp4(frames, tmp_path / path, fps)
    assert list(tmp_path.iterdir()) == []


def test_write_mp4_reports_ffmpeg_failure(tmp_path):
    (tmp_path / "taken.mp4").mkdir()  # ffmpeg cannot open a folder as its output
    with pytest.raises(OSError, match="ffmpeg failed"):
        video.write_mp4(bar_frames(2), tmp_path / "taken.mp4", 15)
    assert (tmp_path / "taken.mp4").is_dir()


def test_missing_video_extra_names_the_pip_command(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # makes `import imageio_ffmpeg` fail
    with pytest.raises(ImportError, match=r"pip install 'octax-gym\[video\]'"):
        video.write_mp4(bar_frames(2), tmp_path / "v.mp4", 15)
    with pytest.raises(ImportError, match=r"octax-gym\[video\]"):
        video.record("Pong", tmp_path / "v.mp4", steps=1, progress=False)


# --- record -----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def videos(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("videos")


@pytest.fixture(scope="module")
def single(videos) -> video.RecordResult:
    return video.record("octax/Pong-v0", videos / "single.mp4", steps=STEPS, policy="noop",
                        render_scale=SCALE, progress=False)


@pytest.fixture(scope="module")
def grid(videos) -> video.RecordResult:
    return video.record("Pong", videos / "grid.mp4", steps=STEPS, policy="noop", num_envs=4,
                        render_scale=SCALE, progress=False)


def test_record_writes_the_first_screen_and_one_frame_per_step(single, videos):
    assert single == video.RecordResult(path=videos / "single.mp4", frames=STEPS + 1, episodes=0,
                                        width=CELL[1], height=CELL[0], fps=15.0)
    frames, fourcc, fps = read_mp4(single.path)
    assert fourcc.lower() in H264_FOURCCS and fps == pytest.approx(15.0)
    assert len(frames) == STEPS + 1 and frames[0].shape == (*CELL, 3)
    assert frames[0].max() > 200 and frames[0].min() < 50  # a Pong screen, not a blank one


def test_record_with_four_envs_writes_a_two_by_two_grid(grid, single):
    gap = 2  # render.tile's grey gap
    assert (grid.frames, grid.width, grid.height) == (STEPS + 1, 2 * CELL[1] + gap, 2 * CELL[0] + gap)
    frames, fourcc, _ = read_mp4(grid.path)
    assert fourcc.lower() in H264_FOURCCS
    assert len(frames) == STEPS + 1 and frames[-1].shape == (grid.height, grid.width, 3)
    lit = frames[-1][..., 0] > 128
    cells = [lit[row: row + CELL[0], col: col + CELL[1]]
             for row in (0, CELL[0] + gap) for col in (0, CELL[1] + gap)]  # row-major: env 0, 1, 2, 3
    # env 0 was seeded like the single env and held no key either: the same screen, top left
    alone = read_mp4(single.path)[0][-1][..., 0] > 128
    assert [int((cell != alone).sum()) <= 2 for cell in cells] == [True, False, False, False]
    separator = frames[-1][:, CELL[1]: CELL[1] + gap]
    assert np.abs(separator.astype(int) - 64).mean() < 12


def test_record_random_policy_follows_the_seed(videos):
    def play(seed):
        result = video.record("Pong", videos / f"random-{seed}.mp4", steps=8, seed=seed, render_scale=SCALE,
                              progress=False)
        return np.stack(read_mp4(result.path)[0])

    first, again, other = play(3), play(3), play(4)
    assert mean_abs_diff(first, again) == 0
    assert mean_abs_diff(first, other) > 0.05


def test_record_counts_the_episodes_that_ended(videos):
    # Cut at 2 steps with next-step autoreset: episodes end at steps 2 and 5 (3 and 6 are resets).
    result = video.record("Pong", videos / "short.mp4", steps=6, policy="noop", max_episode_steps=2,
                          render_scale=SCALE, progress=False)
    assert result.episodes == 2 and result.frames == 7


def test_record_plays_a_policy_function(videos, single):
    seen = []

    def hold_down(obs):
        seen.append(obs.shape)
        return np.full(1, 2)  # action 2: key 4, paddle down

    result = video.record("Pong", videos / "down.mp4", steps=STEPS, policy=hold_down, render_scale=SCALE,
                          progress=False)
    assert seen == [(1, 4, 32, 64)] * STEPS and result.frames == STEPS + 1
    def paddle_row(frame):  # mean row of the lit pixels in the left paddle's column (CHIP-8 x = 2)
        return np.nonzero(frame[:, 2 * SCALE: 3 * SCALE, 0].mean(axis=1) > 128)[0].mean()

    moved, still = read_mp4(result.path)[0][-1], read_mp4(single.path)[0][-1]
    assert paddle_row(moved) > paddle_row(still) + 4 * SCALE


@pytest.mark.parametrize("game, kwargs, match", [
    ("Pong", {"policy": "greedy"}, "'random', 'noop'"),
    ("Pong", {"steps": 0}, "steps must be an int >= 1"),
    ("Pong", {"num_envs": 0}, "num_envs must be an int >= 1"),
    ("Pongg", {}, r"unknown game 'Pongg' \(did you mean 'Pong'\?\); valid: .*'Brix', .*'Pong', .*octax/Airplane-v0"),
    ("octax/Pong-v9", {}, r"unknown game 'octax/Pong-v9' \(did you mean 'octax/Pong-v0'"),
    ("Pong", {"palette": "mauve"}, "'white', 'octo', 'green', 'amber', 'blue'"),
])
def test_record_rejects_bad_arguments_naming_the_valid_ones(tmp_path, game, kwargs, match):
    with pytest.raises(ValueError, match=match):
        video.record(game, tmp_path / "v.mp4", **{"steps": 2, "progress": False, **kwargs})
    assert not (tmp_path / "v.mp4").exists()


def test_record_wants_an_mp4_path(tmp_path):
    with pytest.raises(ValueError, match=r"\.mp4"):
        video.record("Pong", tmp_path / "v.gif", steps=2, progress=False)


# --- octax-gym record -------------------------------------------------------------------------


def test_cli_record_writes_the_video_and_reports_it(tmp_path, capsys):
    path = tmp_path / "pong.mp4"
    status = cli.main(["record", "Pong", "--steps", "3", "--out", str(path), "--scale", str(SCALE),
                       "--palette", "green", "--policy", "noop", "--no-progress"])
    out = capsys.readouterr().out
    assert status == 0
    assert f"wrote {path}: 4 frames, {CELL[1]}x{CELL[0]} at 15 fps" in out and "0 episode(s) ended" in out
    frames, fourcc, _ = read_mp4(path)
    assert len(frames) == 4 and fourcc.lower() in H264_FOURCCS
    red, green, blue = frames[-1].reshape(-1, 3).mean(axis=0)
    assert green > red + 15 and green > blue + 15  # the green palette


@pytest.mark.parametrize("args, expected", [
    (["Pong", "--policy", "greedy"], ["unknown policy 'greedy'", "'random'", "'noop'"]),
    (["Pongg"], ["unknown game 'Pongg'", "Pong", "Tetris"]),
    (["Pong", "--palette", "mauve"], ["unknown palette 'mauve'", "amber"]),
    (["Pong", "--envs", "0"], ["num_envs must be an int >= 1, got 0"]),
    (["Pong", "--steps", "0"], ["steps must be an int >= 1, got 0"]),
    (["Pong", "--scale", "0"], ["render_scale must be an int in 1..64, got 0"]),
])
def test_cli_record_errors_name_the_valid_choices(tmp_path, capsys, args, expected):
    argv = ["record", *args, "--no-progress", "--out", str(tmp_path / "v.mp4")]
    if "--steps" not in args:
        argv += ["--steps", "2"]
    assert cli.main(argv) == 1
    err = capsys.readouterr().err
    assert err.startswith("octax-gym: error: ")
    for text in expected:
        assert text in err
    assert not (tmp_path / "v.mp4").exists()


def test_cli_record_help_lists_every_policy_and_palette(capsys):
    with pytest.raises(SystemExit) as exit_info:
        cli.main(["record", "--help"])
    assert exit_info.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    for name in [*POLICIES, *render.PALETTES]:
        assert name in text


# --- Gymnasium's RecordVideo ------------------------------------------------------------------

# moviepy 2.1.2, which RecordVideo writes with, drops a clip's last frame for many lengths (6 or 7
# frames at 15 fps, not 21): ImageSequenceClip sums n float durations of 1/fps and truncates
# n/fps*fps (moviepy issue #2507). 20 steps make 21 frames, a length it keeps.
WRAPPER_STEPS = 20


def test_gymnasium_record_video_on_a_single_env(tmp_path):
    env = gym.make("octax/Pong-v0", render_mode="rgb_array", render_scale=SCALE)
    env = gym.wrappers.RecordVideo(env, str(tmp_path / "rv"), episode_trigger=lambda episode: episode == 0)
    env.reset(seed=0)
    for _ in range(WRAPPER_STEPS):
        env.step(env.action_space.sample())
    env.close()
    assert [p.name for p in (tmp_path / "rv").iterdir()] == ["rl-video-episode-0.mp4"]
    frames, fourcc, fps = read_mp4(tmp_path / "rv" / "rl-video-episode-0.mp4")
    assert len(frames) == WRAPPER_STEPS + 1 and frames[0].shape == (*CELL, 3)  # reset + each step
    assert fourcc.lower() in H264_FOURCCS and fps == pytest.approx(15.0)
    assert "yuv420p" in video_stream(tmp_path / "rv" / "rl-video-episode-0.mp4")


def test_gymnasium_record_video_on_a_vector_env(tmp_path):
    envs = gym.make_vec("octax/Pong-v0", num_envs=4, render_mode="rgb_array", render_scale=SCALE)
    envs = gym.wrappers.vector.RecordVideo(envs, str(tmp_path / "rv"),
                                           episode_trigger=lambda episode: episode == 0)
    envs.reset(seed=0)
    for _ in range(WRAPPER_STEPS):
        envs.step(envs.action_space.sample())
    envs.close()
    assert [p.name for p in (tmp_path / "rv").iterdir()] == ["rl-video-episode-0.mp4"]
    frames, fourcc, fps = read_mp4(tmp_path / "rv" / "rl-video-episode-0.mp4")
    assert len(frames) == WRAPPER_STEPS + 1
    assert frames[0].shape == (2 * CELL[0], 2 * CELL[1], 3)  # Gymnasium's 2 x 2 grid has no gaps
    assert fourcc.lower() in H264_FOURCCS and fps == pytest.approx(15.0)


def test_env_ids_are_what_record_accepts():
    assert all(resolve_env_id(gym_id) == gym_id for gym_id in octax_gym.ENV_IDS)


def test_gymnasium_record_video_splits_vector_episodes_at_our_autoresets(tmp_path):
    # Episodes cut at 5 steps: env 0 ends at steps 5 and 11 (6 and 12 are its next-step resets),
    # and the wrapper starts a new file after each end.
    envs = gym.make_vec("octax/Pong-v0", num_envs=4, render_mode="rgb_array", render_scale=SCALE,
                        max_episode_steps=5)
    envs = gym.wrappers.vector.RecordVideo(envs, str(tmp_path / "rv"), episode_trigger=lambda episode: True)
    envs.reset(seed=0)
    for _ in range(12):
        envs.step(envs.action_space.sample())
    envs.close()
    assert sorted(p.name for p in (tmp_path / "rv").iterdir()) == [
        f"rl-video-episode-{episode}.mp4" for episode in range(3)]
