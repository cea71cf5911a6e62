import sys

from .book import main

sys.exit(main())
