"""The grader's runtime, which only grading runs and a learner's kernel never imports: the probes that
build the hidden tests' inputs and encode what comes out (``probes``), the probe server that runs
them in a sandbox of its own (``probe_server``), and the kernel factory (``zygote``).
"""
