// The machine's own timer floor, for comparison with `rig latency`'s sample-instant jitter
// (README, "Latency budget"): a bare loop under the realtime plant's policy — SCHED_FIFO,
// mlockall, an absolute sleep to `spin` µs before each instant, then a spin to it — that
// reports the jitter (first clock reading at or after the instant, minus the instant).
//
//   gcc -O2 -o /tmp/bare_loop bench/scripts/bare_loop.c
//   /tmp/bare_loop CYCLES PERIOD_MS SPIN_US PRIORITY     # e.g. 10000 30 2000 51 (root)

#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <sched.h>
#include <sys/mman.h>
#include <stdint.h>
static uint64_t now(void){struct timespec t;clock_gettime(CLOCK_MONOTONIC,&t);return (uint64_t)t.tv_sec*1000000000ull+t.tv_nsec;}
int cmp(const void*a,const void*b){uint64_t x=*(uint64_t*)a,y=*(uint64_t*)b;return x<y?-1:x>y;}
int main(int argc,char**argv){
  int n=atoi(argv[1]); uint64_t period=(uint64_t)(atof(argv[2])*1e6), spin=(uint64_t)atoi(argv[3])*1000; int prio=atoi(argv[4]);
  if(prio>0){struct sched_param p={.sched_priority=prio}; if(sched_setscheduler(0,SCHED_FIFO,&p)) {perror("sched");return 1;} mlockall(MCL_CURRENT|MCL_FUTURE);}
  uint64_t *j=malloc(n*8); uint64_t t=now()+period;
  for(int i=0;i<n;i++,t+=period){
    uint64_t w=t-spin; struct timespec ts={w/1000000000ull,w%1000000000ull};
    if(now()<w) clock_nanosleep(CLOCK_MONOTONIC,TIMER_ABSTIME,&ts,NULL);
    uint64_t x; while((x=now())<t); j[i]=x-t;
  }
  qsort(j,n,8,cmp);
  printf("cycles %d period %.3f ms spin %llu us prio %d: jitter p50 %.1f p90 %.1f p99 %.1f p99.9 %.1f max %.1f us\n",n,period/1e6,(unsigned long long)spin/1000,prio,
    j[n/2]/1e3,j[n*9/10]/1e3,j[n*99/100]/1e3,j[n*999/1000]/1e3,j[n-1]/1e3);
}
