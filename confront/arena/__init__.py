"""confront.arena"""
