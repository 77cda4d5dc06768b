"""``python -m synth``: the command line (``synth.cli``)."""

from .cli import main

if __name__ == "__main__":
    main(prog_name="python -m synth")
