"""What a net's build writes: design.json (:mod:`.design_json`), report.md and the summary
(:mod:`.report`), and the views from above and the side (:mod:`.preview`).
"""
