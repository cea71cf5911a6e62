"""A stand-in for Colab's own ``google.colab``, for `make colab-check` (scripts/colab_check.py).

Colab imports ``google.colab`` into every kernel before the first cell runs; the chapter's
notebooks only ask whether it is there (``"google.colab" in sys.modules``) to decide whether to
install their package. The lane copies this folder's ``google/`` into .venv-colab and imports
it from an IPython startup file, as Colab does. Nothing else of Colab is imitated.
"""

STANDIN = True
