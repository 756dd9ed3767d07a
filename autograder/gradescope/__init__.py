"""Grading on Gradescope: a bundle built in one command, graded in Gradescope's own layout.

``python -m autograder gradescope a1 --out a1_autograder.zip [--seed-file F]`` builds the
zip (:mod:`.bundle`); on Gradescope its ``setup.sh`` installs the grader and its
``run_autograder`` grades each submission (:mod:`.run`) into a results.json
(:mod:`autograder.gradescope_json`) that follows Gradescope's documented format
(:mod:`autograder.gradescope_schema`).
See the Gradescope section of ``assignments/README.md``.
"""
