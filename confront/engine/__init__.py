"""confront.engine"""
