"""``python -m stsf_gym.cli``: the ``stsf-gym`` command."""

import sys

from stsf_gym.cli import main

sys.exit(main())
