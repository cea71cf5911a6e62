"""nbgrader course configuration: the course lives in this folder, its gradebook in gradebook.db.

The instructor notebooks in ../solutions are the single source; scripts/release.py copies them to
source/<assignment>/ here, runs `nbgrader generate_assignment`, and publishes the student release
to ../notebooks.
"""
import os

c = get_config()  # noqa: F821 (provided by nbgrader)
HERE = os.path.dirname(os.path.abspath(__file__))
c.CourseDirectory.root = HERE
c.CourseDirectory.course_id = "zero2robot-ch3.2"
c.CourseDirectory.db_url = "sqlite:///" + os.path.join(HERE, "gradebook.db")
c.ClearSolutions.code_stub = {"python": "# YOUR CODE HERE\nraise NotImplementedError()"}
c.ClearSolutions.text_stub = "YOUR ANSWER HERE"
c.ClearOutput.enabled = True
c.Execute.timeout = 120            # seconds per cell; a student's infinite loop cannot hang grading
