"""The LLM path against a real local HTTP server speaking the chat-completions API."""

import hashlib
import http.server
import json
import threading
from pathlib import Path

import pytest

from octax_core.generate import chat, filters, llm, prompt
from octax_gym.cli import main

REPO = Path(__file__).resolve().parents[2]
DODGE = (REPO / "roms" / "dodge.8o").read_text()
BROKEN = "Here is the game.\n```octo\n: main\n\tv0 := 1\n\tjump nowhere\n```\nscore: v5\n"
FIXED = f"Fixed.\n```\n{DODGE}```\nscore: v5\ngame over: vE == 1\nlives: v6\nkeys: 1 4 6\n"
TINY = ["--frames", "400", "--end-limit", "100", "--horizon", "40", "--beam", "2", "--random-lanes", "1"]


class Server:
    """Answers the first request with a program that does not assemble, every later one with
    roms/dodge.8o; keeps what it was sent."""

    def __init__(self):
        self.requests = []
        outer = self

        class Handler(http.server.BaseHTTPRequestHandler):
            def do_POST(self):
                body = json.loads(self.rfile.read(int(self.headers["Content-Length"])))
                outer.requests.append({"path": self.path, "body": body, "auth": self.headers.get("Authorization")})
                reply = BROKEN if len(outer.requests) == 1 else FIXED
                data = json.dumps({"id": "x", "object": "chat.completion", "model": body["model"],
                                   "choices": [{"index": 0, "finish_reason": "stop",
                                                "message": {"role": "assistant", "content": reply}}]}).encode()
                self.send_response(200)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def log_message(self, *args):
                pass

        self.httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}/v1"
        self.thread = threading.Thread(target=self.httpd.serve_forever, daemon=True)


@pytest.fixture
def server():
    running = Server()
    running.thread.start()
    yield running
    running.httpd.shutdown()
    running.httpd.server_close()


def test_a_broken_program_is_repaired_and_archived(server, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("OCTAX_TEST_KEY", "sk-test")
    judged = []

    def fake_check(specs, roms, settings):  # the filters are tests/generate/test_filters.py's
        judged.extend(roms)
        return [filters.Verdict(("made up",), 0.0, 0.0, 0.0) for _ in specs]
    monkeypatch.setattr(filters, "check", fake_check)
    out = tmp_path / "llm"
    assert main(["generate", "--llm-url", server.url, "--model", "tiny", "--description", "dodge falling rocks",
                 "--count", "1", "--repairs", "2", "--api-key-env", "OCTAX_TEST_KEY", "--trace-steps", "100",
                 "--out", str(out), *TINY]) == 0
    assert "llm-0000: assembled after 2 replies" in capsys.readouterr().out
    first, second = server.requests
    assert first["path"] == "/v1/chat/completions" and first["auth"] == "Bearer sk-test"
    assert first["body"]["model"] == "tiny"
    opening = first["body"]["messages"][0]["content"]
    assert "professional CHIP-8 (classic version) game developer" in opening
    assert "<description>dodge falling rocks</description>" in opening
    # the second turn: the whole conversation, the assembler's message (line, column, caret) last
    sent_back = second["body"]["messages"]
    assert [m["role"] for m in sent_back] == ["user", "assistant", "user"]
    assert "line 3, column 7" in sent_back[-1]["content"] and "nowhere" in sent_back[-1]["content"]
    game, = json.loads((out / "archive.json").read_text())["games"]
    assert game["sha1"] == hashlib.sha1((REPO / "roms" / "dodge.ch8").read_bytes()).hexdigest()
    assert game["registers"] == {"score": 5, "lives": 6, "end": [14, 1]}
    assert game["action_keys"] == [1, 4, 6] and game["registers_found"].startswith("stated in the reply")
    assert (out / "llm-0000.ch8").read_bytes() == (REPO / "roms" / "dodge.ch8").read_bytes()
    assert judged == [(REPO / "roms" / "dodge.ch8").read_bytes()] and game["reasons"] == ["made up"]


def test_without_repairs_the_assembler_message_is_the_reason(server, tmp_path):
    out = tmp_path / "llm"
    assert main(["generate", "--llm-url", server.url, "--model", "tiny", "--description", "x", "--repairs", "0",
                 "--count", "1", "--out", str(out), *TINY]) == 0
    game, = json.loads((out / "archive.json").read_text())["games"]
    assert not game["accepted"] and game["rom"] is None
    assert game["reasons"][0].startswith("does not assemble: line 3, column 7")
    assert len(server.requests) == 1


def test_usage_and_server_errors(tmp_path, capsys):
    assert main(["generate", "--llm-url", "http://127.0.0.1:9/v1", "--model", "m", "--description", "x",
                 "--out", str(tmp_path)]) == 1
    assert "cannot reach the LLM server at http://127.0.0.1:9/v1/chat/completions" in capsys.readouterr().err
    assert main(["generate", "--llm-url", "ftp://x", "--model", "m", "--description", "x",
                 "--out", str(tmp_path)]) == 1
    assert "must start with http:// or https://" in capsys.readouterr().err
    assert main(["generate", "--llm-url", "http://127.0.0.1:9", "--model", "m", "--out", str(tmp_path)]) == 1
    assert "needs --llm-url URL, --model M, --out DIR and --description TEXT" in capsys.readouterr().err
    assert main(["generate", "--llm-url", "http://127.0.0.1:9", "--model", "m", "--description", "x",
                 "--prompt-part", "manual=x.md", "--out", str(tmp_path)]) == 1
    assert "unknown prompt part 'manual'; valid: documentation, tutorial1, tutorial2, example" in capsys.readouterr().err


def test_the_reply_is_read_for_its_program_and_registers():
    assert llm.program_of("no fence: clear") == "no fence: clear"
    assert llm.program_of("a\n```octo\nclear\n```\n```\nother\n```") == "clear\n"
    stated = llm.stated_registers("```\n# score: v1 in a comment\n```\nScore is stored in register v2\n"
                                  "Game over: vA == 0x03\nlives: none\nkeys: 5, 7, a")
    assert stated == {"score": 2, "end": [10, 3], "lives": None, "keys": [5, 7, 10]}
    assert llm.stated_registers("nothing here") == {}


def test_the_prompt_is_the_papers_with_parts_by_path(tmp_path):
    manual = tmp_path / "manual.md"
    manual.write_text("THE MANUAL")
    text = prompt.build_prompt("a catcher", prompt.read_parts({"documentation": str(manual)}))
    assert "<documentation>THE MANUAL</documentation>" in text
    assert ":alias score  v5" in text  # the example: one of our own dodgers
    assert "* The **score** must be stored in a clear and consistent register or memory location." in text
    with pytest.raises(ValueError, match="cannot read"):
        prompt.read_parts({"example": str(tmp_path / "missing.8o")})
    assert chat.endpoint("http://h/v1/") == "http://h/v1/chat/completions"
