"""Generated games: procedural families written in Octo and an LLM's programs, and the checks
that keep the playable ones. See docs/generate.md.

    families   the templates and their parameter ranges (FAMILIES, get_family)
    sample     parameters drawn from a seed;  render  a variant's Octo source
    build      the source assembled, and the GameSpec every variant of every family shares
    filters    the checks every candidate of a round passes, run as one batch (a mix)
    rounds     candidates (a family's variants) judged into archive rows
    archive    archive.json: written byte for byte the same for the same inputs, and read back
    prompt     the paper's prompt and its parts;  chat  the chat-completions API (stdlib only)
    llm        the paper's loop: ask, send the assembler's message back, take the registers
"""
