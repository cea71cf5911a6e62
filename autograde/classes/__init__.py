"""Classes of hand-ins made to test the grader: ``synthetic`` (a small class of typical hand-ins),
``hostile`` (one student per attack on the grader), ``honest`` (really executed honest variants).
None of this is imported by the grader itself."""
