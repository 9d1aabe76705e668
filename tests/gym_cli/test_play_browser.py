"""`octax-gym play` in a real browser: headless Chromium (Debian's chromium + chromium-driver)
driven by Selenium.

The page loads; keys pressed in the browser move the game exactly as the env says (the page's
frames, and the pixels on its canvas, against the env stepped alone with the same actions from
the same seed); pause, single step and reset work; the key press -> frame latency is measured; the
human's episodes, recorded, replay exactly from the Minari dataset; a two-player game's seats can
be changed. Screenshots go to $OCTAX_PLAY_SCREENSHOTS (docs/play to refresh the committed ones),
else to a temporary folder.

Skipped with a reason when Chromium, chromedriver or Selenium is missing, unless
OCTAX_REQUIRE_BROWSER=1 (CI), which fails instead.
"""

from __future__ import annotations

import base64
import os
import shutil
import time
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.browser

REQUIRE_BROWSER = os.environ.get("OCTAX_REQUIRE_BROWSER") == "1"
GAME, TWO_PLAYER_GAME, SEED = "Dodge", "Duel", 11


def _missing() -> str | None:
    try:
        import aiohttp  # noqa: F401
        import selenium  # noqa: F401
    except ImportError as exc:
        return f"needs aiohttp and selenium (the play and dev extras): {exc}"
    if not (shutil.which("chromium") or shutil.which("chromium-browser")):
        return "needs Chromium (apt-get install chromium chromium-driver)"
    if not shutil.which("chromedriver"):
        return "needs chromedriver (apt-get install chromium-driver)"
    return None


@pytest.fixture(scope="module")
def browser():
    why = _missing()
    if why is not None:
        if REQUIRE_BROWSER:
            pytest.fail(f"{why} (OCTAX_REQUIRE_BROWSER=1: this run must have a browser)")
        pytest.skip(why)
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which("chromium") or shutil.which("chromium-browser")
    for argument in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                     "--window-size=1100,820", "--hide-scrollbars", "--force-device-scale-factor=1"):
        options.add_argument(argument)
    driver = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=options)
    driver.set_script_timeout(30)
    yield driver
    driver.quit()


@pytest.fixture(scope="module")
def shots(tmp_path_factory) -> Path:
    folder = Path(os.environ.get("OCTAX_PLAY_SCREENSHOTS") or tmp_path_factory.mktemp("play-shots"))
    folder.mkdir(parents=True, exist_ok=True)
    return folder


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A live Dodge server whose human episodes are recorded into a temporary Minari folder."""
    from octax_gym.play.record import Recorder
    from octax_gym.play.server import start_in_thread
    from octax_gym.play.session import Session
    from octax_gym.envs.vector import OctaxVectorEnv

    before = os.environ.get("MINARI_DATASETS_PATH")
    os.environ["MINARI_DATASETS_PATH"] = str(tmp_path_factory.mktemp("minari"))
    probe = OctaxVectorEnv(GAME, 1)
    recorder = Recorder(GAME, "octax/Dodge-human-v0", observation_space=probe.single_observation_space,
                        num_actions=probe.single_action_space.n, recorder="the browser test")
    session = Session(GAME, seed=SEED, recorder=recorder)
    handle = start_in_thread(session)
    yield handle, session, recorder
    handle.stop()
    if before is None:
        os.environ.pop("MINARI_DATASETS_PATH", None)
    else:
        os.environ["MINARI_DATASETS_PATH"] = before


def wait_for(driver, script: str, timeout: float = 30.0, *args):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = driver.execute_script(script, *args)
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for: {script}")


def open_page(driver, url: str, timeout: float = 30.0) -> None:
    """`driver.get(url)`, then waits until `url`'s document has run its script (`window.octaxPlay`).

    chromedriver can return from `get` while scripts still run in the previous document, the
    browser's first about:blank or the page before (a known race: SeleniumHQ/selenium#1364; seen
    once in a loaded suite as `window.octaxPlay` undefined just after `get`), so the page is polled
    until its own URL answers. A page that never runs its script still fails, naming where the
    browser is and how far it got."""
    driver.get(url)
    try:
        wait_for(driver, "return document.URL === arguments[0] && typeof window.octaxPlay === 'object'", timeout, url)
    except AssertionError:
        where = driver.execute_script("return [document.URL, document.readyState, document.title]")
        raise AssertionError(f"the page's script did not run within {timeout:g} s: at {where[0]!r} "
                             f"(readyState {where[1]!r}, title {where[2]!r})") from None


def press(driver, key: str, hold: float) -> None:
    from selenium.webdriver.common.action_chains import ActionChains

    ActionChains(driver).key_down(key).perform()
    time.sleep(hold)
    ActionChains(driver).key_up(key).perform()


def page_log(driver) -> list[dict]:
    return driver.execute_script("return window.octaxPlay.log.map(m => ({episode: m.episode, seed: m.seed, "
                                 "step: m.step, actions: m.actions, frames: m.frames, done: m.done}))")


def decode(message: dict, shape) -> np.ndarray:
    return np.frombuffer(base64.b64decode(message["frames"]), np.uint8).reshape(shape)


def episode_steps(log: list[dict], episode: int) -> list[dict]:
    """The page's messages of one episode, one per step (the reset's is step 0), in order."""
    steps = {m["step"]: m for m in log if m["episode"] == episode}
    assert sorted(steps) == list(range(len(steps))), "the page missed a step"
    return [steps[i] for i in range(len(steps))]


def replay_frames(game: str, seed: int, actions: list) -> list[np.ndarray]:
    """The env alone, reset with `seed` and stepped with `actions`: each step's frames."""
    from octax_gym.envs.vector import OctaxVectorEnv

    env = OctaxVectorEnv(game, 1, autoreset_mode="disabled")
    obs, _ = env.reset(seed=seed)
    frames = [np.asarray(obs[0])]
    for action in actions:
        obs, *_ = env.step(np.array([action[0]], np.int32))
        frames.append(np.asarray(obs[0]))
    env.close()
    return frames


def canvas_indices(driver, hello: dict) -> np.ndarray:
    """The canvas's pixels, one sampled at each CHIP-8 pixel's centre, as palette indices."""
    rgb = np.array(driver.execute_script("""
        const c = document.getElementById('screen'), h = window.octaxPlay.hello;
        const s = c.width / h.width, d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data, out = [];
        for (let y = 0; y < h.height; y++) for (let x = 0; x < h.width; x++) {
          const i = 4 * ((y * s + (s >> 1)) * c.width + x * s + (s >> 1)); out.push([d[i], d[i + 1], d[i + 2]]); }
        return out;"""), np.int32).reshape(hello["height"], hello["width"], 3)
    palette = np.array(hello["palette"], np.int32)
    match = (rgb[:, :, None, :] == palette[None, None]).all(-1)
    assert match.any(-1).all(), "the canvas holds a colour outside the game's palette"
    return match.argmax(-1)


def test_play_in_the_browser(browser, recorded, shots):
    handle, session, recorder = recorded
    driver = browser
    open_page(driver, handle.url)
    hello = wait_for(driver, "return window.octaxPlay.hello")
    wait_for(driver, "return window.octaxPlay.log.length > 3 && window.octaxPlay.drawn > 3")
    assert hello["game"] == GAME and GAME in driver.title
    shape = (hello["frames_per_step"], hello["height"], hello["width"])
    keys = [action["keyboard"].lower() for action in hello["seats"][0]["actions"]]
    driver.execute_script("window.focus(); document.body.focus();")  # keys go to the page

    # Keys: hold each of the game's keys in turn, with gaps, timing press -> frame each time.
    for _ in range(3):
        for key in keys:
            press(driver, key, 0.35)
            time.sleep(0.15)
    if not shots.joinpath("dodge.png").exists() or os.environ.get("OCTAX_PLAY_SCREENSHOTS"):
        driver.save_screenshot(str(shots / "dodge.png"))
    driver.find_element("tag name", "body").send_keys(" ")  # Space: pause
    wait_for(driver, "return window.octaxPlay.state && window.octaxPlay.state.paused")
    time.sleep(0.3)
    paused_at = handle.call(lambda: session.step_count)
    time.sleep(0.5)
    assert handle.call(lambda: session.step_count) == paused_at, "the game moved while paused"

    latencies = [entry["ms"] for entry in driver.execute_script("return window.octaxPlay.latencies")]
    log = page_log(driver)
    episode = log[-1]["episode"]
    steps = episode_steps(log, episode)
    actions = [m["actions"] for m in steps[1:]]
    assert {a[0] for a in actions} >= {1, 2, 0}, f"the keys did not reach the game: {actions}"
    expected = replay_frames(GAME, steps[0]["seed"], actions)
    for message, frames in zip(steps, expected):
        assert np.array_equal(decode(message, shape), frames), f"step {message['step']} differs from the env"
    noop = replay_frames(GAME, steps[0]["seed"], [[0]] * len(actions))
    assert not np.array_equal(noop[-1], expected[-1]), "the keys changed nothing on the screen"
    time.sleep(0.2)  # the last frames drawn
    assert np.array_equal(canvas_indices(driver, hello), expected[-1][-1]), "the canvas is not the env's last frame"

    # One step while paused ('.'), then reset (Enter): a new episode from the next seed.
    driver.find_element("tag name", "body").send_keys(".")
    wait_for(driver, f"return window.octaxPlay.last.step === {len(actions) + 1}")
    driver.find_element("tag name", "body").send_keys("\n")
    wait_for(driver, f"return window.octaxPlay.last.episode === {episode + 1}")
    last = driver.execute_script("return window.octaxPlay.last")
    assert (last["step"], last["seed"], last["return"]) == (0, SEED + episode + 1, [0.0])
    assert np.array_equal(decode(last, shape), replay_frames(GAME, SEED + episode + 1, [])[0])

    # The second episode: play a little more, and time more key presses, at full speed.
    driver.find_element("tag name", "body").send_keys(" ")
    wait_for(driver, "return window.octaxPlay.state && !window.octaxPlay.state.paused")
    for key in keys * 2:
        press(driver, key, 0.3)
        time.sleep(0.15)
    latencies = [entry["ms"] for entry in driver.execute_script("return window.octaxPlay.latencies")]
    fps = handle.call(session.frames_per_second)
    print(f"\nkey press -> first frame of the step that played it, in the browser: {len(latencies)} presses, "
          f"median {np.median(latencies):.0f} ms, p90 {np.percentile(latencies, 90):.0f} ms, "
          f"max {max(latencies):.0f} ms; of which on the server (key message in -> its step done): median "
          f"{1000 * np.median(session.key_wait):.0f} ms; server {fps:.1f} frames/s; step compute median "
          f"{1000 * np.median(session.step_seconds):.2f} ms")
    assert len(latencies) >= 10 and np.median(latencies) < 150
    assert 54 <= fps <= 61  # 60 frames/s, a 10% margin for a loaded CI machine

    # Recording: stop the server (the episode in play is written, cut), then replay every episode.
    handle.stop()
    session.close()
    dataset = recorder.close()
    check_replays(dataset, min_episodes=2)


def check_replays(dataset, min_episodes: int) -> None:
    from octax_gym.datasets import episode_seed

    assert dataset.total_episodes >= min_episodes
    assert dataset.storage.metadata["algorithm_name"] == "human"
    assert "the browser test" in dataset.storage.metadata["author"]  # Minari keeps authors as a set
    env = dataset.recover_environment()
    moved = False
    for episode in dataset.iterate_episodes():
        obs, info = env.reset(seed=episode_seed(dataset, episode.id))
        assert np.array_equal(obs, episode.observations[0])
        assert set(episode.infos) >= {"score", "lives", "episode_step"}
        for t, action in enumerate(episode.actions):
            obs, reward, terminated, truncated, info = env.step(int(action))
            assert np.array_equal(obs, episode.observations[t + 1]), f"episode {episode.id} step {t}"
            assert reward == episode.rewards[t] and terminated == episode.terminations[t]
            assert info["score"] == episode.infos["score"][t + 1] and info["lives"] == episode.infos["lives"][t + 1]
        moved |= bool(np.any(episode.actions != 0))
    assert moved
    env.close()


def test_two_player_page_seats(browser, shots):
    from octax_gym.play.server import start_in_thread
    from octax_gym.play.session import Session

    session = Session(TWO_PLAYER_GAME, seed=2)
    handle = start_in_thread(session)
    try:
        driver = browser
        open_page(driver, handle.url)
        hello = wait_for(driver, "return window.octaxPlay.hello")
        assert [s["name"] for s in hello["seats"]] == ["left paddle", "right paddle"]
        assert hello["players"] == ["human", "scripted", "random"]
        wait_for(driver, "return window.octaxPlay.log.length > 3")
        driver.execute_script("window.focus(); document.body.focus();")
        left_down = hello["seats"][0]["actions"][1]["keyboard"].lower()
        for _ in range(4):
            press(driver, left_down, 0.4)
            time.sleep(0.1)
        wait_for(driver, "return window.octaxPlay.log.length > 60", timeout=20)
        if not shots.joinpath("duel.png").exists() or os.environ.get("OCTAX_PLAY_SCREENSHOTS"):
            driver.save_screenshot(str(shots / "duel.png"))
        from selenium.webdriver.support.ui import Select

        Select(driver.find_element("id", "seat0")).select_by_value("random")
        Select(driver.find_element("id", "seat1")).select_by_value("human")
        wait_for(driver, "return window.octaxPlay.state.players.join() === 'random,human'")
        assert handle.call(lambda: list(session.players)) == ["random", "human"]
        log = page_log(driver)
        assert any(m["actions"][0] == 2 for m in log), "the left paddle's key did not reach the game"
        # The page's frames are the env's, stepped with the logged actions of both seats.
        from octax_gym import MultiAgentVectorEnv

        steps = episode_steps(log, log[-1]["episode"])
        env = MultiAgentVectorEnv(TWO_PLAYER_GAME, 1, autoreset_mode="disabled")
        obs, _ = env.reset(seed=steps[0]["seed"])
        shape = (hello["frames_per_step"], hello["height"], hello["width"])
        for message in steps[1:]:
            obs, *_ = env.step(np.array([message["actions"]], np.int32))
            assert np.array_equal(decode(message, shape), np.asarray(obs[0, 0, :shape[0]]))
        env.close()
    finally:
        handle.stop()
        session.close()
