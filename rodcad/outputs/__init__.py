"""What a build writes for people and programs: design.json, report.md, summaries, previews.
"""
