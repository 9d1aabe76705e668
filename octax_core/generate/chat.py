"""The OpenAI-compatible chat-completions API, with the standard library only.

vLLM, llama.cpp's server, Ollama and the hosted APIs all take `POST {base}/chat/completions`
with {"model", "messages"} and answer {"choices": [{"message": {"content": ...}}]}; that is all
the LLM loop (`octax_core.generate.llm`) needs, so no client library is imported.
"""

from __future__ import annotations

import json
import urllib.error
import urllib.request
from typing import Optional, Sequence

TIMEOUT_S = 600  # a long program from a slow local model


def endpoint(url: str) -> str:
    """`url` with `/chat/completions` added, unless it already ends so (".../v1" -> ".../v1/chat/completions")."""
    if not url.startswith(("http://", "https://")):
        raise ValueError(f"the LLM URL must start with http:// or https://, got {url!r}")
    url = url.rstrip("/")
    return url if url.endswith("/chat/completions") else f"{url}/chat/completions"


def complete(url: str, model: str, messages: Sequence[dict], api_key: Optional[str] = None,
             temperature: Optional[float] = None, timeout: float = TIMEOUT_S) -> str:
    """The first choice's text for `messages`.

    Raises:
        ValueError: the server refused (its status and message), could not be reached, or
            answered something that is not a chat completion.
    """
    body = {"model": model, "messages": list(messages)}
    if temperature is not None:
        body["temperature"] = temperature
    headers = {"Content-Type": "application/json"}
    if api_key:
        headers["Authorization"] = f"Bearer {api_key}"
    request = urllib.request.Request(endpoint(url), data=json.dumps(body).encode(), headers=headers, method="POST")
    try:
        with urllib.request.urlopen(request, timeout=timeout) as response:
            answer = json.loads(response.read().decode("utf-8"))
    except urllib.error.HTTPError as exc:
        detail = exc.read().decode("utf-8", "replace")[:500]
        raise ValueError(f"the LLM server at {endpoint(url)} answered {exc.code}: {detail}") from None
    except urllib.error.URLError as exc:
        raise ValueError(f"cannot reach the LLM server at {endpoint(url)}: {exc.reason}") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"the LLM server at {endpoint(url)} answered something that is not JSON: {exc}") from None
    try:
        content = answer["choices"][0]["message"]["content"]
    except (KeyError, IndexError, TypeError):
        raise ValueError(f"the LLM server at {endpoint(url)} answered no choices[0].message.content: "
                         f"{json.dumps(answer)[:300]}") from None
    if not isinstance(content, str):
        raise ValueError(f"the LLM server at {endpoint(url)} answered a content that is not text: {content!r}")
    return content
