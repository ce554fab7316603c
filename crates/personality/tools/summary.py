"""Print a one-line-per-entry summary of an EDS (review aid)."""
import re, sys
def summary(path, lo=0, hi=0xFFFF):
    sec=None; d={}
    out=[]
    def flush():
        if sec and re.fullmatch(r'[0-9A-F]{4}(sub[0-9A-F]+)?', sec):
            i=int(sec[:4],16)
            if lo<=i<=hi and 'DataType' in d:
                out.append(f"{sec:10} {d.get('ParameterName','')[:40]:40} t={d['DataType'][-2:]} {d.get('AccessType'):5} def={d.get('DefaultValue','')} lim={d.get('LowLimit','')}..{d.get('HighLimit','')} pdo={d.get('PDOMapping')}")
    for line in open(path):
        line=line.strip()
        if line.startswith('['):
            flush(); sec=line[1:-1]; d={}
        elif '=' in line:
            k,v=line.split('=',1); d[k]=v
    flush()
    return out
if __name__=='__main__':
    for l in summary(sys.argv[1], int(sys.argv[2],16), int(sys.argv[3],16)): print(l)
